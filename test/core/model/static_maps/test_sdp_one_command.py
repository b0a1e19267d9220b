"""One command's speed on an eq. (5) map is the array path's, bit for bit."""

from hydro_sdp.core.model.static_maps.sdp import sdp_rate, SdpMap
import numpy as np
import pytest


@pytest.mark.parametrize('parameters', [(-30.0, 0.08, -4.0, 25.0, 0.12, 5.0),
                                        (-0.3, 1.9, 0.0, 0.35, 2.2, 0.0),
                                        (-50.0, 0.01, -40.0, 45.0, 0.02, 37.0)])
def test_one_command_equals_the_array_path(parameters):
    rng = np.random.default_rng(11)
    commands = np.r_[rng.uniform(-120.0, 120.0, 5000), rng.normal(0.0, 1e-3, 500),
                     parameters[2], parameters[5], 0.0, -0.0, np.inf, -np.inf, np.nan]
    canonical = sdp_rate(commands, *parameters)
    one = np.array([sdp_rate(np.array([v]), *parameters)[0] for v in commands])
    assert np.array_equal(one, canonical, equal_nan=True)
    scalar = sdp_rate(commands[0], *parameters)
    assert isinstance(scalar, np.float64) and scalar == canonical[0]
    assert sdp_rate(np.array([[commands[1]]]), *parameters).shape == (1, 1)


def test_the_maps_rate_of_one_command_is_its_rate_in_a_record():
    chosen = SdpMap((-4.0, 5.0), (-30.0, 25.0), (0.04, 0.06))
    commands = np.linspace(-100.0, 100.0, 401)
    assert np.array_equal([chosen.rate(np.array([v]))[0] for v in commands],
                          chosen.rate(commands))

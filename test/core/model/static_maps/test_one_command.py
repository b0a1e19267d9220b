"""One command's speed on an eq. (5) or a power_sat map is the array path's, bit for bit."""

from hydro_sdp.core.model.static_maps.power_sat import power_sat_rate, PowerSatMap
from hydro_sdp.core.model.static_maps.sdp import sdp_rate, SdpMap
import numpy as np
import pytest

# numpy takes the exponents 2 and 0.5 as a square and a square root, not as pow().
EXPONENTS = [(0.5, 2.0), (1.0, 1.0), (2.0, 0.5), (1.7, 3.0), (0.3, 2.5)]
CASES = [(power_sat_rate, (-30.0, 0.04, n, -4.0, 25.0, 0.06, p, 5.0)) for n, p in EXPONENTS] + [
    (sdp_rate, (-30.0, 0.08, -4.0, 25.0, 0.12, 5.0)),
    (sdp_rate, (-0.3, 1.9, 0.0, 0.35, 2.2, 0.0)),
    (sdp_rate, (-50.0, 0.01, -40.0, 45.0, 0.02, 37.0))]


@pytest.mark.parametrize('rate, parameters', CASES)
def test_one_command_equals_the_array_path(rate, parameters):
    rng = np.random.default_rng(7)
    # The parameters among the commands: the dead-zone's edges, whichever the family.
    commands = np.r_[rng.uniform(-120.0, 120.0, 5000), rng.normal(0.0, 1e-3, 500),
                     parameters, 0.0, -0.0, np.inf, -np.inf, np.nan]
    canonical = rate(commands, *parameters)
    one = np.array([rate(np.array([v]), *parameters)[0] for v in commands])
    assert np.array_equal(one, canonical, equal_nan=True)
    scalar = rate(commands[0], *parameters)
    assert isinstance(scalar, np.float64) and scalar == canonical[0]
    assert rate(np.array([[commands[1]]]), *parameters).shape == (1, 1)


def test_an_overflowing_command_takes_the_array_path():
    # (c u)^n beyond a float: the array path's inf and its warning, not an exception.
    parameters = (-30.0, 1e100, 3.0, -4.0, 25.0, 1e100, 3.0, 5.0)
    with pytest.warns(RuntimeWarning):
        one = power_sat_rate(np.array([1e200]), *parameters)
    with pytest.warns(RuntimeWarning):
        canonical = power_sat_rate(np.array([1e200, 0.0]), *parameters)
    assert one[0] == canonical[0] == 25.0


@pytest.mark.parametrize('chosen', [PowerSatMap((-4.0, 5.0), (-30.0, 25.0), (0.04, 0.06),
                                                (2.0, 1.5)),
                                    SdpMap((-4.0, 5.0), (-30.0, 25.0), (0.04, 0.06))])
def test_the_maps_rate_of_one_command_is_its_rate_in_a_record(chosen):
    commands = np.linspace(-100.0, 100.0, 401)
    assert np.array_equal([chosen.rate(np.array([v]))[0] for v in commands],
                          chosen.rate(commands))

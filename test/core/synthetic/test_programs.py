"""Input programs: command ranges from the model, and joints kept off their end stops."""

from hydro_sdp.core.errors import ConfigurationError
from hydro_sdp.core.model.joint_model import JointModel
from hydro_sdp.core.model.simulation import simulate
from hydro_sdp.core.model.static_maps import LinearMap, SdpDzMap, SdpMap
from hydro_sdp.core.synthetic.programs import (
    level_bounds, random_program, start_angle, step_program)
import numpy as np
import pytest

# A valve driven in percent duty whose dead-zone does not contain zero.
DUTY = JointModel('arm', SdpMap((40.0, 58.0), (-12.0, 15.0), (0.08, 0.1)), 0.2,
                  angle_limits=(-30.0, 90.0), input_limits=(0.0, 100.0))


def _levels(v):
    """Held levels of a program, in order."""
    change = np.flatnonzero(np.diff(v)) + 1
    return v[np.r_[0, change]]


def test_j2_steps_alternate_and_grow(j2):
    v = step_program(j2, 0.01, steps=40, y0=start_angle(j2))
    levels = _levels(v)
    steps = levels[1::2]
    assert np.all(levels[::2] == 0.0)           # rests between the steps
    assert steps.size == 40
    magnitudes = np.abs(steps)
    assert magnitudes[-1] > 3.5 and magnitudes[0] < 1.3298   # from inside the dead-zone
    assert np.sum(steps > 0) == np.sum(steps < 0) == 20
    assert np.all(np.diff(magnitudes[steps > 0]) > 0)
    assert np.all(np.diff(magnitudes[steps < 0]) > 0)


@pytest.mark.parametrize('seed', range(5))
def test_programs_keep_the_joint_off_its_end_stops(j2, seed):
    y0 = start_angle(j2)
    for v in (step_program(j2, 0.01, y0=y0), random_program(j2, 0.01, 300.0, seed=seed, y0=y0)):
        y = simulate(j2, v, 0.01, y0)
        assert -13.8 < y.min() and y.max() < 63.6
        assert np.all(np.abs(v) <= 10.0)


def test_random_program_is_seeded_and_varied(j2):
    a = random_program(j2, 0.01, 120.0, seed=3, y0=20.0)
    b = random_program(j2, 0.01, 120.0, seed=3, y0=20.0)
    c = random_program(j2, 0.01, 120.0, seed=4, y0=20.0)
    np.testing.assert_array_equal(a, b)
    assert not np.array_equal(a, c)
    assert a.size == 12000
    levels = _levels(a)
    assert np.any(levels > 1.3124) and np.any(levels < -1.3298)
    assert np.any((levels > -1.3298) & (levels < 1.3124))


def test_percent_duty_valve(rng):
    assert DUTY.rest_command == pytest.approx(49.0)
    (small_neg, large_neg), (small_pos, large_pos) = level_bounds(DUTY)
    assert 40.0 < small_neg < 49.0 < small_pos < 58.0
    assert 0.0 <= large_neg < 40.0 and 58.0 < large_pos <= 100.0
    y0 = start_angle(DUTY)
    for v in (step_program(DUTY, 0.02, y0=y0), random_program(DUTY, 0.02, 200.0, y0=y0)):
        assert v.min() >= 0.0 and v.max() <= 100.0
        y = simulate(DUTY, v, 0.02, y0)
        assert -30.0 < y.min() and y.max() < 90.0


def test_maps_without_saturation_or_dead_zone():
    for model in (JointModel('j', LinearMap(12.0), 0.1, input_limits=(-10.0, 10.0)),
                  JointModel('j', SdpDzMap((-1.0, 1.0), (20.0, 30.0)), 0.1)):
        v = random_program(model, 0.05, 60.0, y0=0.0)
        y = simulate(model, v, 0.05, 0.0)
        # Without end stops the programs keep to +-30 deg, give or take one delay of travel.
        assert np.abs(y).max() < 40.0


def test_bad_program_settings(j2):
    with pytest.raises(ConfigurationError, match='at least 2 steps'):
        step_program(j2, 0.01, steps=1)
    with pytest.raises(ConfigurationError, match='duration'):
        random_program(j2, 0.01, 0.0)
    with pytest.raises(ConfigurationError, match='sample period'):
        random_program(j2, -0.01, 10.0)

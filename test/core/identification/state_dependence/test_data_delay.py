"""The analysis's delay is the one identify finds, for held steps and for commands never held."""

from hydro_sdp.core.identification.state_dependence.analysis import data_delay
from hydro_sdp.core.model.records import Record
import numpy as np
import pytest

DT = 0.01


def _integrator(v, delay, seed):
    # A dead-zone of 5 and a gain of 0.5 deg/s per unit, the command ``delay`` samples late.
    speed = np.where(np.abs(v) > 5.0, 0.5 * (v - 5.0 * np.sign(v)), 0.0)
    late = np.r_[np.zeros(delay), speed[:-delay]]
    return np.cumsum(late) * DT + np.random.default_rng(seed).normal(0.0, 0.01, v.size)


@pytest.mark.parametrize('delay', [5, 12, 30])
def test_a_command_that_never_rests_gives_its_delay(delay):
    # A sweep with no change windows: the delay of routine operation.
    t = np.arange(4000) * DT
    v = 20.0 * np.sin(2.0 * np.pi * 0.3 * t) + 25.0
    record = Record(t, v, _integrator(v, delay, delay), joint='j')
    assert data_delay([record], DT, 0.5, 0.0) == delay


@pytest.mark.parametrize('delay', [8, 25])
def test_held_steps_give_their_delay(delay):
    levels = np.r_[0.0, 30.0, 0.0, -25.0, 0.0, 40.0, 0.0, -45.0, 0.0]
    v = np.repeat(levels, 300)
    t = np.arange(v.size) * DT
    record = Record(t, v, _integrator(v, delay, delay), joint='j')
    assert data_delay([record], DT, 0.5, 0.0) == delay

"""The timing rule: known answers, and a bag round trip that keeps the simulated trajectory."""

import math
from pathlib import Path
import tempfile

from hydro_sdp.bags import read_bag, write_bag
from hydro_sdp.core.errors import ConfigurationError
from hydro_sdp.core.model.joint_model import JointModel
from hydro_sdp.core.model.records import Record
from hydro_sdp.core.model.simulation import JointSimulator, simulate
from hydro_sdp.core.model.static_maps import SdpMap
from hydro_sdp.core.model.timing import (
    command_in_force, command_stamps_for, delay_samples, delayed, delayed_at, DelayLine,
    SamplePeriod)
from hypothesis import given, HealthCheck, settings, strategies as st
import numpy as np
import pytest


def test_sample_period_is_a_checked_float():
    assert SamplePeriod(0.01) == 0.01 and SamplePeriod(1) == 1.0
    assert repr(SamplePeriod(0.01)) == '0.01' and f'{SamplePeriod(0.05):g}' == '0.05'
    assert SamplePeriod(np.float64(0.02)) == 0.02 and SamplePeriod(np.int64(2)) == 2.0
    for bad in (0.0, -0.01, math.nan, math.inf, '0.01', None, True):
        with pytest.raises(ConfigurationError) as refused:
            SamplePeriod(bad)
        assert str(refused.value) == (f'sample period must be a positive number of seconds, '
                                      f'got {bad!r}')


@pytest.mark.parametrize('delay, dt, samples', [
    (0.15, 0.05, 3),      # 0.15 / 0.05 is 2.9999999999999996 in floating point
    (0.15, 0.01, 15),
    (0.12, 0.01, 12),
    (0.025, 0.01, 3),     # ties go up
    (0.014, 0.01, 1),
    (0.0, 0.01, 1),       # a command moves the joint one sample later at the earliest
    (0.004, 0.01, 1),
])
def test_delay_samples(delay, dt, samples):
    assert delay_samples(delay, dt) == samples


def test_delayed():
    values = np.array([1.0, 2.0, 3.0, 4.0])
    np.testing.assert_array_equal(delayed(values, 0), values)
    np.testing.assert_array_equal(delayed(values, 2), [1.0, 1.0, 1.0, 2.0])
    np.testing.assert_array_equal(delayed(values, 2, before=0.0), [0.0, 0.0, 1.0, 2.0])
    np.testing.assert_array_equal(delayed(values, 9, before=-1.0), [-1.0] * 4)
    assert delayed(np.zeros(0), 3).size == 0
    with pytest.raises(ConfigurationError, match='>= 0'):
        delayed(values, -1)


def test_delayed_at_holds_the_first_value_before_the_start():
    values = np.array([10.0, 20.0, 30.0, 40.0])
    np.testing.assert_array_equal(delayed_at(values, np.array([0, 1, 3]), 2), [10.0, 10.0, 20.0])
    np.testing.assert_array_equal(delayed_at(values, np.arange(4), 1),
                                  delayed(values, 1))


def test_command_in_force_is_the_last_one_before_the_sample():
    commands = np.array([0.5, 2.0, 2.5])
    samples = np.array([0.4, 1.0, 2.0, 3.0, 4.0])
    # A command stamped exactly at a sample answers that sample: not yet in force there.
    np.testing.assert_array_equal(command_in_force(samples, commands), [-1, 0, 0, 2, 2])


def test_command_stamps_for_are_one_sample_early():
    samples = np.array([100, 110, 125], dtype=np.int64)
    np.testing.assert_array_equal(command_stamps_for(samples), [90, 100, 110])
    np.testing.assert_array_equal(command_in_force(samples, command_stamps_for(samples)),
                                  [0, 1, 2])


def test_delay_line():
    line = DelayLine(2, before=5.0)
    assert [line.delayed(tau) for tau in range(3)] == [5.0, 5.0, 5.0]
    line.push(1.0)
    line.push(2.0)
    assert [line.delayed(tau) for tau in range(3)] == [2.0, 1.0, 5.0]
    line.push(3.0)
    assert [line.delayed(tau) for tau in range(3)] == [3.0, 2.0, 1.0]
    with pytest.raises(ConfigurationError):
        DelayLine(-1, 0.0)


def test_delay_line_agrees_with_delayed():
    values = np.random.default_rng(1).normal(size=50)
    line = DelayLine(4, before=0.5)
    out = []
    for value in values:
        line.push(value)
        out.append(line.delayed(4))
    np.testing.assert_array_equal(out, delayed(values, 4, before=0.5))


@st.composite
def experiments(draw):
    """Draw a random SDP joint, command sequence, sample period and (jittered) time stamps."""
    dt = draw(st.sampled_from([0.005, 0.01, 0.02, 0.05]))
    low = draw(st.floats(0.0, 2.0))
    high = draw(st.floats(0.0, 2.0))
    speeds = (-draw(st.floats(5.0, 60.0)), draw(st.floats(5.0, 60.0)))
    shapes = (draw(st.floats(0.3, 3.0)), draw(st.floats(0.3, 3.0)))
    delay = draw(st.floats(0.0, 0.3))
    limits = draw(st.sampled_from([None, (-30.0, 30.0)]))
    model = JointModel('j', SdpMap((-low, high), speeds, shapes), delay, angle_limits=limits)
    levels = draw(st.lists(st.floats(-10.0, 10.0), min_size=2, max_size=8))
    holds = draw(st.lists(st.integers(1, 40), min_size=len(levels), max_size=len(levels)))
    v = np.repeat(levels, holds)
    seed = draw(st.integers(0, 2 ** 16))
    first = draw(st.integers(3, 1000))
    # Stamps wander around the nominal instants, as a loaded timer's do.
    jitter = np.random.default_rng(seed).uniform(-0.3, 0.3, v.size) * dt
    t = (first + np.arange(v.size)) * dt + jitter
    storage = draw(st.sampled_from(['sqlite3', 'mcap']))
    return model, v, t, dt, storage


@settings(max_examples=30, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(experiments(), st.floats(-20.0, 20.0))
def test_a_bag_round_trip_keeps_the_simulated_trajectory(example, y0):
    model, v, t, dt, storage = example
    expected = simulate(model, v, dt, y0, v_before=float(v[0]))
    with tempfile.TemporaryDirectory() as folder:
        bag = write_bag(Path(folder) / 'bag', [Record(t, v, expected, joint='j')],
                        storage=storage)
        data = read_bag(bag)
        back = data.record()
    assert len(back) == v.size
    np.testing.assert_array_equal(back.v, v)
    np.testing.assert_allclose(back.t + data.start * 1e-9, t, atol=1e-9)
    again = simulate(model, back.v, dt, y0, v_before=float(back.v[0]))
    np.testing.assert_array_equal(again, expected)
    # The sample-by-sample simulator that drives the loops agrees as well.
    simulator = JointSimulator(model, dt, y0, v_before=float(back.v[0]))
    stepped = [simulator.angle] + [simulator.step(float(command)) for command in back.v[1:]]
    np.testing.assert_allclose(stepped, expected, rtol=0, atol=1e-9)

"""
A time axis as loggers and DDS give it: the controller runs every whole number of samples.

A 10 ms raster read on a clock that runs 0.09 % fast (0.0099909 s apart) or a DDS timer at
0.00998 s is the same machine as one at 0.01 s: the same samples per control step, the
same delay in samples, the same map per sample and the same gains. Only the seconds scale.
"""

from dataclasses import replace

from hydro_sdp.core.control.controller_spec import design_from_model
from hydro_sdp.core.control.loop_simulation import LoopJoint, run_closed_loop, step_setpoints
from hydro_sdp.core.errors import ConfigurationError
from hydro_sdp.core.identification.identify import identify
from hydro_sdp.core.model.records import Record
from hydro_sdp.core.model.sample_period import (
    control_period_on, control_steps, PERIOD_TOLERANCE)
import numpy as np
import pytest
from support.plain_joint import PlainJoint, steps

#: The joint, driven in percent duty (independent of the package's simulator).
JOINT = PlainJoint(delay=9, dead_zone=(-14.0, 11.0), slope=(0.9, 1.1), saturation=(30.0, 36.0),
                   stops=(-50.0, 60.0), noise=0.02)
#: Relative agreement of what identify finds per sample (speed x period): the fits stop at
#: their optimisers' tolerance (a few 1e-6), far inside the parameters' standard errors.
PER_SAMPLE = 2e-5


@pytest.mark.parametrize(('asked', 'dt', 'samples', 'seconds'), [
    (0.05, 0.01, 5, 0.05), (0.05, 0.0099909, 5, 0.0499545), (0.05, 0.00998, 5, 0.0499),
    (0.05, 0.0125, 4, 0.05), (0.05, 0.02, 3, 0.06),          # 2.5 samples: ties go up
    (0.05, 1 / 30, 2, 0.06666666666667), (0.001, 0.01, 1, 0.01)])
def test_the_control_period_is_the_nearest_whole_multiple(asked, dt, samples, seconds):
    period = control_period_on(asked, dt)
    assert (period.samples, period.seconds, period.asked) == (samples, seconds, asked)


def test_a_controller_runs_on_a_plant_within_the_tolerance_and_not_beyond(j2):
    assert control_steps(0.0499545, 0.01) == control_steps(0.05, 0.00998) == 5
    assert control_steps(0.05 * (1 + 0.9 * PERIOD_TOLERANCE), 0.01) == 5
    with pytest.raises(ConfigurationError, match=r'the control period 0.05 s must be a whole '
                       r'multiple of the plant period 0.03 s \(within 1%; it is 1.667 periods\)'):
        control_steps(0.05, 0.03)
    # A controller designed on a 0.0099909 s recording steps every 5 samples of a 0.01 s
    # plant, and its gains per control sample are those of 0.05 s: the same loop.
    at = {period: design_from_model(j2, control_period=period) for period in (0.05, 0.0499545)}
    traces = [run_closed_loop([LoopJoint(j2, spec.controller(),
                                         step_setpoints([10.0], 3.0, 0.01))],
                              dt=0.01, control_period=spec.control_period)[0]
              for spec in at.values()]
    np.testing.assert_allclose(traces[0].y, traces[1].y, rtol=1e-3, atol=1e-3)
    assert at[0.05].gains == at[0.0499545].gains


def _runs():
    """Return steps on both sides and random levels, per sample (a 10 ms raster's dynamics)."""
    levels = [25.0, -25.0, 45.0, -45.0, 100.0, -100.0]
    return [JOINT.run(steps(levels, hold=1.0, rest=0.6), seed=1),
            JOINT.run_levels(8.0, magnitude=(15.0, 100.0), seed=2)]


def _on_axis(records, period, jitter=0.0, seed=0):
    """Put the same samples on another time axis: ``period`` apart, jittered +-``jitter`` s."""
    rng = np.random.default_rng(seed)
    out = []
    for record in records:
        k = np.arange(1, len(record) + 1)
        t = k * period + rng.uniform(-jitter, jitter, k.size)
        out.append(Record(t, record.v, record.y, joint='arm', source=record.source))
    return out


def _model_and_controller(records):
    found = identify(records, input_limits=(-100.0, 100.0))
    period = control_period_on(0.05, found.sample_period)
    return found, period, design_from_model(found.model, control_period=period.seconds)


@pytest.fixture(scope='module')
def reference():
    records = _runs()
    return records, _model_and_controller(_on_axis(records, 0.01))


@pytest.mark.parametrize(('period', 'jitter'), [(0.0099909, 0.0), (0.00998, 0.0),
                                                (0.00998, 0.5e-3)],
                         ids=['logger_clock', 'dds_timer', 'dds_timer_jitter'])
def test_a_period_off_a_round_one_gives_the_same_model_and_controller(
        reference, period, jitter):
    records, (at_round, control_round, spec_round) = reference
    found, control, spec = _model_and_controller(_on_axis(records, period, jitter, seed=3))
    dt, round_dt = found.sample_period, at_round.sample_period
    # The jittered DDS timer reads as 0.01 s or as 0.00998 s, a coin: the answer is one.
    assert round_dt == 0.01 and abs(dt / period - 1.0) < (2.5e-3 if jitter else 1e-4)
    model, round_model = found.model, at_round.model
    # Same delay and control step in samples; the seconds are those samples of this axis.
    assert model.delay_samples(dt) == round_model.delay_samples(0.01) == JOINT.delay
    assert control.samples == control_round.samples == 5
    assert control.seconds == pytest.approx(5 * dt, rel=1e-12)
    # The same map per sample: speeds scale by 0.01 / dt.
    assert model.kind == round_model.kind
    grid = np.linspace(-100.0, 100.0, 81)
    np.testing.assert_allclose(model.rate(grid) * dt, round_model.rate(grid) * 0.01,
                               rtol=PER_SAMPLE, atol=1e-9)
    # The same controller: gains, delay, IDZ (deg per control sample) and limits.
    assert spec.gains == spec_round.gains
    assert spec.delay_samples == spec_round.delay_samples
    np.testing.assert_allclose(spec.idz.slopes, spec_round.idz.slopes, rtol=PER_SAMPLE)
    np.testing.assert_allclose(spec.idz.dead_zone, spec_round.idz.dead_zone, rtol=PER_SAMPLE)
    np.testing.assert_allclose(spec.u_limits, spec_round.u_limits, rtol=PER_SAMPLE)
    # Designed at the asked 0.05 s instead, the DDS timer's controller would differ by the
    # 0.2 % of the clock (what the nearest whole multiple removes).
    if period == 0.00998 and dt == 0.00998:
        asked = design_from_model(replace(model), control_period=0.05)
        assert not np.allclose(asked.idz.slopes, spec_round.idz.slopes, rtol=1e-3)

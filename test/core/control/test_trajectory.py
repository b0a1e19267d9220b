"""Joint trajectories: validation, sampling as JointTrajectoryController does, feed-forward."""

import math

from hydro_sdp.core.control.controller_spec import design_from_model
from hydro_sdp.core.control.loop_simulation import LoopJoint, run_closed_loop
from hydro_sdp.core.control.pip_controller import ControllerSettings, PipIdzController
from hydro_sdp.core.control.pip_design import PipGains
from hydro_sdp.core.control.trajectory import (
    check_trajectory, check_trajectory_speeds, JointTrajectory, start_time, TrajectorySampler)
from hydro_sdp.core.errors import DataError
import numpy as np
import pytest

PAPER = PipGains((0.1261,), (0.12, 0.1261), 0.0061)
LIMITS = {'boom': (-40.0, 50.0), 'dipper': (-150.0, -30.0)}


def trajectory(times, positions, velocities=None, names=('boom', 'dipper')):
    return JointTrajectory(tuple(names), np.array(times, dtype=float),
                           np.array(positions, dtype=float),
                           None if velocities is None else np.array(velocities, dtype=float))


@pytest.mark.parametrize('names, times, positions, message', [
    (('boom', 'boom'), [1.0], [[0.0, 0.0]], 'repeated: boom'),
    (('boom',), [1.0, 1.0], [[0.0], [1.0]], 'strictly increasing'),
    (('boom',), [2.0, 1.0], [[0.0], [1.0]], 'strictly increasing'),
    (('boom',), [-1.0], [[0.0]], '>= 0 s'),
    (('boom',), [math.nan], [[0.0]], 'finite'),
    (('boom',), [1.0], [[math.inf]], 'positions must be finite'),
    (('boom',), [1.0, 2.0], [[0.0]], 'one row per point'),
    ((), [1.0], [[0.0]], 'needs joint names'),
])
def test_invalid_trajectories_are_refused(names, times, positions, message):
    with pytest.raises(DataError, match=message):
        trajectory(times, positions, names=names)


def test_velocities_must_match_the_positions():
    with pytest.raises(DataError, match='shape of the positions'):
        trajectory([1.0], [[0.0, -90.0]], [[0.0]])


def test_refusal_names_every_unknown_joint_and_every_joint_beyond_the_stops():
    bad = JointTrajectory(('stick', 'boom', 'dipper', 'bucket'), np.array([1.0, 2.0]),
                          np.array([[0.0, 10.0, -90.0, 0.0], [0.0, 49.6, -160.0, 0.0]]))
    with pytest.raises(DataError) as error:
        check_trajectory(bad, LIMITS)
    text = str(error.value)
    assert text.startswith('trajectory refused: joints not controlled: stick, bucket')
    assert 'boom reaches 49.6 deg (allowed [-39.5, 49.5])' in text
    assert 'dipper reaches -160 deg (allowed [-149.5, -30.5])' in text
    # Inside the end stops less the margin: accepted; a larger margin refuses the same.
    good = trajectory([1.0], [[49.5, -30.5]])
    check_trajectory(good, LIMITS)
    with pytest.raises(DataError, match='less 1 deg: boom reaches 49.5'):
        check_trajectory(good, LIMITS, margin=1.0)


def test_a_zero_stamp_starts_now():
    assert start_time(0.0, 12.5) == 12.5
    assert start_time(20.0, 12.5) == 20.0


def test_linear_sampling_holds_before_blends_from_the_held_setpoint_and_holds_after():
    sampler = TrajectorySampler({'boom': 5.0, 'dipper': -90.0})
    sampler.replace(trajectory([2.0, 6.0], [[15.0, -90.0], [35.0, -50.0]]), start=10.0)
    assert sampler.sample('boom', 9.99) == (5.0, 0.0)             # before the start: held
    # First segment from the set-point held at the start (5 deg at t = 10 s) to the
    # first point (15 deg at 12 s).
    assert sampler.sample('boom', 11.0) == pytest.approx((10.0, 5.0))
    assert sampler.sample('boom', 12.0) == pytest.approx((15.0, 5.0))
    assert sampler.sample('boom', 14.0) == pytest.approx((25.0, 5.0))
    assert sampler.sample('dipper', 14.0) == pytest.approx((-70.0, 10.0))
    assert sampler.sample('dipper', 11.0) == pytest.approx((-90.0, 0.0))
    assert sampler.sample('boom', 16.0) == (35.0, 0.0)            # the end: held, rate 0
    assert sampler.sample('boom', 100.0) == (35.0, 0.0)
    assert sampler.end_time('boom') == 16.0
    assert sampler.end_time('dipper') == 16.0
    assert sampler.sample_all(14.0) == {'boom': pytest.approx((25.0, 5.0)),
                                        'dipper': pytest.approx((-70.0, 10.0))}
    assert TrajectorySampler({'boom': 1.0}).end_time('boom') == -math.inf


def test_a_first_point_at_time_zero_is_a_jump():
    sampler = TrajectorySampler({'boom': 5.0})
    sampler.replace(trajectory([0.0, 1.0], [[20.0], [30.0]], names=('boom',)), start=1.0)
    assert sampler.setpoint('boom', 0.999) == 5.0
    assert sampler.sample('boom', 1.0) == pytest.approx((20.0, 10.0))


def test_cubic_hermite_where_velocities_are_given():
    sampler = TrajectorySampler({'boom': 0.0})
    sampler.replace(trajectory([0.0, 2.0], [[0.0], [10.0]], [[0.0], [0.0]], names=('boom',)),
                    start=0.0)
    # Smoothstep: half-way at mid-time with 1.5 x the mean speed, at rest at both ends.
    assert sampler.sample('boom', 1.0) == pytest.approx((5.0, 7.5))
    assert sampler.sample('boom', 0.0) == pytest.approx((0.0, 0.0))
    assert sampler.sample('boom', 0.5) == pytest.approx((10.0 * (3 * 0.0625 - 2 * 0.015625),
                                                         10.0 * 6 * (0.25 - 0.0625) / 2.0))
    # The rate is the derivative of the set-point, and the given end velocities are met.
    sampler.replace(trajectory([1.0, 3.0], [[4.0], [-2.0]], [[3.0], [-1.0]], names=('boom',)),
                    start=10.0)
    for t in (10.3, 10.8, 11.7, 12.5):      # inside the segments, off the points
        h = 1e-6
        slope = (sampler.setpoint('boom', t + h) - sampler.setpoint('boom', t - h)) / (2 * h)
        assert sampler.sample('boom', t)[1] == pytest.approx(slope, rel=1e-6, abs=1e-6)
    assert sampler.sample('boom', 11.0) == pytest.approx((4.0, 3.0))
    assert sampler.sample('boom', 13.0 - 1e-9)[1] == pytest.approx(-1.0, abs=1e-6)
    # The first segment starts from the held set-point (10 deg at t = 10 s) at the rate in force.
    assert sampler.sample('boom', 10.0) == pytest.approx((10.0, 0.0))


def test_a_new_trajectory_replaces_the_rest_of_the_old_one_from_its_start():
    sampler = TrajectorySampler({'boom': 0.0, 'dipper': -90.0})
    sampler.replace(trajectory([10.0], [[40.0, -50.0]]), start=0.0)     # 4 deg/s, 4 deg/s
    sampler.replace(trajectory([2.0], [[0.0]], names=('boom',)), start=5.0)
    assert sampler.setpoint('boom', 4.0) == pytest.approx(16.0)          # old one until 5 s
    assert sampler.setpoint('boom', 5.0) == pytest.approx(20.0)          # continuous at 5 s
    assert sampler.sample('boom', 6.0) == pytest.approx((10.0, -10.0))   # back to 0 by 7 s
    assert sampler.setpoint('boom', 8.0) == 0.0
    assert sampler.setpoint('dipper', 8.0) == pytest.approx(-58.0)       # not named: goes on
    # A trajectory starting earlier than one planned later drops the later one.
    sampler.replace(trajectory([1.0], [[30.0]], names=('boom',)), start=4.0)
    assert sampler.setpoint('boom', 5.0) == pytest.approx(30.0)
    assert sampler.setpoint('boom', 8.0) == 30.0
    sampler.hold('dipper', -80.0, 9.0)
    assert sampler.sample('dipper', 9.5) == (-80.0, 0.0)
    with pytest.raises(DataError, match='joints not controlled: stick'):
        sampler.replace(trajectory([1.0], [[0.0]], names=('stick',)), start=0.0)


def test_pruning_keeps_what_is_ahead():
    sampler = TrajectorySampler({'boom': 0.0})
    sampler.replace(trajectory([10.0], [[40.0]], names=('boom',)), start=0.0)
    sampler.replace(trajectory([2.0], [[0.0]], names=('boom',)), start=5.0)
    times = np.linspace(6.0, 9.0, 13)
    before = sampler.setpoints('boom', times)
    sampler.prune(6.0)
    np.testing.assert_array_equal(sampler.setpoints('boom', times), before)


def test_feedforward_is_the_setpoint_increment_lead_periods_ahead():
    sampler = TrajectorySampler({'boom': 0.0})
    sampler.replace(trajectory([10.0], [[50.0]], names=('boom',)), start=1.0)  # 5 deg/s
    assert sampler.feedforward('boom', 5.0, 0.05, 3) == pytest.approx(0.25)
    assert sampler.feedforward('boom', 0.8, 0.05, 3) == 0.0
    # Three periods ahead of 0.875 s lies the period (0.975, 1.025] s: half of it moves.
    assert sampler.feedforward('boom', 0.875, 0.05, 3) == pytest.approx(0.125)
    assert sampler.feedforward('boom', 0.9, 0.05, 3) == pytest.approx(0.25)
    assert sampler.feedforward('boom', 10.9, 0.05, 3) == 0.0


def _integrator_ramp(feedforward, rate=0.2, tau=3, samples=1200):
    """Run the PIP on y_k = y_{k-1} + u_{k-tau} following d_k = rate * k from k = 100."""
    controller = PipIdzController(ControllerSettings(PAPER))
    d = np.maximum(np.arange(samples + tau + 1) - 100, 0) * rate
    y = np.zeros(samples)
    u = np.zeros(samples)
    for k in range(samples):
        if k:
            y[k] = y[k - 1] + (u[k - tau] if k >= tau else 0.0)
        ahead = d[k + tau] - d[k + tau - 1]
        u[k] = controller.step(d[k], y[k], ahead if feedforward else None)[0]
    return d[:samples] - y


def test_feedforward_removes_the_ramp_lag_on_the_integrator():
    rate = 0.2
    lag = PAPER.f[0] * rate / PAPER.k_i          # 4.13 deg (docs/methods.md, f0 r / kI)
    plain = _integrator_ramp(False, rate)
    assert plain[-1] == pytest.approx(lag, rel=1e-6)
    fed = _integrator_ramp(True, rate)
    # The error obeys the regulator's loop, which nothing excites: tracking is exact.
    assert np.max(np.abs(fed)) < 1e-9


def test_feedforward_on_j2_tracks_a_ramp(j2):
    spec = design_from_model(j2, control_period=0.05)
    dt, tc = 0.01, spec.control_period
    t = np.arange(int(25.0 / dt)) * dt
    errors = {}
    for fed in (False, True):
        sampler = TrajectorySampler({'j2': 0.0})
        sampler.replace(trajectory([15.0], [[45.0]], names=('j2',)), start=2.0)   # 3 deg/s
        setpoint = sampler.setpoints('j2', t)
        ahead = (np.array([sampler.feedforward('j2', x, tc, spec.delay_samples) for x in t])
                 if fed else None)
        trace = run_closed_loop([LoopJoint(j2, spec.controller(), setpoint, 0.0, ahead)],
                                dt=dt, control_period=tc)[0]
        errors[fed] = trace.setpoint - trace.y
    steady = (t > 12.0) & (t < 17.0)
    lag = spec.gains.f[0] * 3.0 * tc / spec.gains.k_i
    # Without feed-forward the lag is f0 r / kI whatever the valve map (u is steady).
    assert np.mean(errors[False][steady]) == pytest.approx(lag, rel=0.05)
    assert np.max(np.abs(errors[True][steady])) < 0.05 * lag
    assert abs(errors[True][-1]) < 0.5


def test_feedforward_of_zero_on_a_held_setpoint_is_the_plain_law(j2, rng):
    spec = design_from_model(j2)
    plain, fed = spec.controller(), spec.controller()
    for y in rng.uniform(-5.0, 25.0, 300):
        assert fed.step(20.0, float(y), 0.0) == plain.step(20.0, float(y))


def test_feedforward_history_excludes_the_feedforward_and_respects_the_limits():
    settings = ControllerSettings(PAPER, u_limits=(-1.0, 1.0))
    controller = PipIdzController(settings)
    controller.reset(y=0.0)
    u, v = controller.step(0.0, 0.0, 0.4)
    assert (u, v) == (0.4, 0.4)                  # no error: only the feed-forward moves
    u, v = controller.step(0.0, 0.0, 0.4)
    assert u == pytest.approx(0.4)                # not integrated into the history
    assert controller.step(0.0, 0.0, 5.0)[0] == 1.0          # clamped to the u limits
    # A feed-forward the limits cut does not push the next command against the motion.
    assert controller.step(0.0, 0.0, 0.0)[0] == pytest.approx(0.0, abs=1e-12)
    # The controller's own part, cut by the limits, is kept at the limit (no wind-up).
    controller = PipIdzController(settings)
    for _ in range(100):
        u, _ = controller.step(60.0, 0.0, 0.5)
    assert u == 1.0
    assert controller._u[0] == 1.0
    with pytest.raises(DataError, match='feed-forward must be finite'):
        controller.step(0.0, 0.0, math.nan)


def test_planned_rates_run_from_the_setpoint_in_force_through_every_segment():
    sampler = TrajectorySampler({'boom': 10.0, 'dipper': -90.0})
    plan = trajectory([1.0, 3.0], [[20.0, -90.0], [0.0, -80.0]])
    # Boom: 10 -> 20 in 1 s, then 20 -> 0 in 2 s; dipper: still, then +5 deg/s.
    assert sampler.planned_rates(plan, 5.0) == {'boom': (-10.0, 10.0), 'dipper': (0.0, 5.0)}
    # A first point at time 0 is a jump (as a set-point step), not a rate.
    jump = trajectory([0.0, 2.0], [[40.0, -90.0], [44.0, -90.0]])
    assert sampler.planned_rates(jump, 5.0)['boom'] == (0.0, 2.0)
    # Nothing changed: the sampler still holds its set-points.
    assert sampler.sample('boom', 100.0) == (10.0, 0.0)


def test_the_cubic_peak_rate_is_found_between_the_points():
    sampler = TrajectorySampler({'boom': 0.0})
    # From 0 at rest to 10 deg at rest in 1 s: the cubic peaks at 1.5 x the chord, mid-way.
    plan = trajectory([1.0], [[10.0]], [[0.0]], names=('boom',))
    low, high = sampler.planned_rates(plan, 0.0)['boom']
    assert low == 0.0 and high == pytest.approx(15.0)
    # Velocities themselves count: 1e6 rad/s given at a point.
    fast = trajectory([1.0, 2.0], [[0.0], [1.0]], [[math.degrees(1e6)], [0.0]], names=('boom',))
    assert sampler.planned_rates(fast, 0.0)['boom'][1] > 5e7


def test_a_trajectory_faster_than_a_joint_is_refused_naming_it():
    tops = {'boom': (-29.5, 38.9), 'dipper': None}
    check_trajectory_speeds({'boom': (-29.0, 38.0), 'dipper': (-1e9, 1e9)}, tops)
    with pytest.raises(DataError, match=r'trajectory refused: faster than the joint can move: '
                                        r'boom at 6000 deg/s \(top speed up 38\.9\)'):
        check_trajectory_speeds({'boom': (0.0, 6000.0)}, tops)
    with pytest.raises(DataError, match=r'boom at -30 deg/s \(top speed down -29\.5\)'):
        check_trajectory_speeds({'boom': (-30.0, 0.0)}, tops)

"""The feedback gate and control schedule: monotonic stamps, freshness, instants, watchdog."""

from hydro_sdp.core.control.controller_spec import design_from_model
from hydro_sdp.core.control.loop_simulation import LoopJoint, run_closed_loop, step_setpoints
from hydro_sdp.core.control.scheduling import (
    ControlSchedule, FeedbackGate, seconds_to_ns, watchdog_period_ns)
from hydro_sdp.core.errors import ConfigurationError, DataError
import numpy as np
import pytest

MS = 1_000_000


def test_stamps_must_increase_duplicates_and_overtaken_samples_are_ignored():
    gate = FeedbackGate(500 * MS, now_ns=0)
    assert gate.admit(100 * MS, now_ns=100 * MS) == 'accepted'
    assert gate.admit(100 * MS, now_ns=101 * MS) == 'ignored'      # duplicate
    assert gate.admit(90 * MS, now_ns=102 * MS) == 'ignored'       # overtaken
    assert gate.last_stamp == 100 * MS and gate.last_valid_ns == 100 * MS
    assert gate.admit(110 * MS, now_ns=110 * MS) == 'accepted'
    assert gate.last_stamp == 110 * MS


def test_freshness_is_judged_against_the_clock_both_ways():
    gate = FeedbackGate(500 * MS, now_ns=0)
    assert gate.admit(1000 * MS, now_ns=1500 * MS) == 'accepted'    # exactly the timeout
    with pytest.raises(DataError, match=r'0\.501 s behind the node clock'):
        gate.admit(1100 * MS, now_ns=1601 * MS)
    with pytest.raises(DataError, match=r'2\.000 s ahead of the node clock'):
        gate.admit(4000 * MS, now_ns=2000 * MS)
    assert gate.last_stamp == 1000 * MS          # a refused sample changes nothing
    # A clock at 0 is simulated time that has not started: no freshness check.
    assert FeedbackGate(500 * MS, now_ns=0).admit(10**12, now_ns=0) == 'accepted'


def test_watchdog_fires_once_then_stays_blind_until_feedback_resumes():
    gate = FeedbackGate(200 * MS, now_ns=1000 * MS)
    assert gate.watchdog(1200 * MS) == 'fed'              # silence == timeout: still fed
    assert gate.watchdog(1201 * MS) == 'lost'
    assert gate.blind and gate.silence_ns(1300 * MS) == 300 * MS
    assert gate.watchdog(1300 * MS) == 'blind'
    assert gate.admit(1350 * MS, now_ns=1350 * MS) == 'resumed'
    assert not gate.blind and gate.watchdog(1400 * MS) == 'fed'
    assert gate.admit(1360 * MS, now_ns=1400 * MS) == 'accepted'


def test_the_timeout_can_change_and_is_checked():
    gate = FeedbackGate(500 * MS, now_ns=0)
    assert gate.watchdog(400 * MS) == 'fed'
    gate.timeout_ns = 300 * MS
    assert gate.timeout_ns == 300 * MS and gate.watchdog(400 * MS) == 'lost'
    with pytest.raises(DataError, match='0.350 s behind'):
        gate.admit(50 * MS, now_ns=400 * MS)
    for bad in (0, -1, 0.5, True):
        with pytest.raises(ConfigurationError):
            gate.timeout_ns = bad
    assert watchdog_period_ns(500 * MS) == 100 * MS       # at most 0.1 s
    assert watchdog_period_ns(60 * MS) == 30 * MS         # half the timeout
    assert seconds_to_ns(0.05) == 50 * MS and seconds_to_ns(1e-9) == 1


def test_control_instants_every_period_from_the_first_sample():
    schedule = ControlSchedule(50 * MS)
    stamps = [7 * MS + k * 10 * MS for k in range(12)]
    ticks = []
    for stamp in stamps:
        tick = schedule.tick(stamp)
        ticks.append(tick)
        if tick != 'wait':
            schedule.stepped(stamp)
    # The first step starts from rest, then every fifth sample.
    assert ticks == ['resume', 'wait', 'wait', 'wait', 'wait', 'step',
                     'wait', 'wait', 'wait', 'wait', 'step', 'wait']
    assert schedule.next_instant == 7 * MS + 150 * MS and schedule.missed == 0


def test_a_late_sample_is_controlled_and_missed_instants_are_skipped():
    schedule = ControlSchedule(50 * MS)
    schedule.stepped(0)
    assert schedule.tick(49 * MS) == 'wait'
    assert schedule.tick(51 * MS) == 'step'          # first sample at or after the instant
    assert schedule.stepped(51 * MS) == 0 and schedule.next_instant == 100 * MS
    assert schedule.tick(230 * MS) == 'step'         # 100 and 150 missed, 200 taken late
    assert schedule.stepped(230 * MS) == 2 and schedule.next_instant == 250 * MS
    assert schedule.missed == 2


def test_after_the_valve_was_closed_the_next_step_starts_from_rest():
    schedule = ControlSchedule(50 * MS)
    assert schedule.holding and schedule.tick(0) == 'resume'
    schedule.stepped(0)
    assert not schedule.holding
    schedule.hold()
    assert schedule.tick(10 * MS) == 'wait'          # not yet an instant: still holding
    assert schedule.holding and schedule.tick(50 * MS) == 'resume'
    schedule.stepped(50 * MS)
    assert schedule.tick(100 * MS) == 'step'
    with pytest.raises(ConfigurationError):
        ControlSchedule(0)


def test_the_offline_loop_controls_at_the_schedules_instants(j2):
    # Controller period 0.03 s on a 0.01 s plant: the command changes only every third sample,
    # and the answer to y_j is in force from sample j + 1 on.
    setpoint = step_setpoints([20.0], 1.0, 0.01)
    trace = run_closed_loop([LoopJoint(j2, design_from_model(j2, control_period=0.03)
                                       .controller(), setpoint, 0.0)],
                            dt=0.01, control_period=0.03)[0]
    changes = np.flatnonzero(np.diff(trace.v)) + 1
    assert changes.size > 5 and np.all((changes - 1) % 3 == 0)
    assert trace.v[0] == 0.0 and trace.v[1] > 1.0       # rest before the first answer


def test_a_stamp_ahead_by_more_than_the_lead_is_refused_and_nothing_changes():
    gate = FeedbackGate(500 * MS, now_ns=0, lead_ns=50 * MS)
    assert gate.admit(1000 * MS, now_ns=1000 * MS) == 'accepted'
    assert gate.admit(1050 * MS, now_ns=1010 * MS) == 'accepted'     # 40 ms ahead: a skew
    with pytest.raises(DataError, match=r'0\.450 s ahead of the node clock \(more than 0\.05 s'):
        gate.admit(1470 * MS, now_ns=1020 * MS)
    # The real samples after it are taken: the one from the future did not move the order.
    assert gate.last_stamp == 1050 * MS
    assert gate.admit(1060 * MS, now_ns=1060 * MS) == 'accepted'


def test_a_stale_stamp_is_refused_before_the_order_is_looked_at():
    gate = FeedbackGate(500 * MS, now_ns=0, lead_ns=50 * MS)
    assert gate.admit(100_000 * MS, now_ns=100_000 * MS) == 'accepted'
    # 100 s behind: older than the last stamp too, but stale first: refused, not ignored.
    with pytest.raises(DataError, match=r'100\.000 s behind'):
        gate.admit(0, now_ns=100_000 * MS)
    assert gate.admit(99_990 * MS, now_ns=100_010 * MS) == 'ignored'  # overtaken, fresh


def test_a_clock_that_goes_back_restarts_the_order_and_the_silence():
    # A simulation restarted: the clock and the stamps start again from 0.
    gate = FeedbackGate(500 * MS, now_ns=0, lead_ns=50 * MS)
    assert gate.admit(60_000 * MS, now_ns=60_000 * MS) == 'accepted'
    assert gate.watchdog(10 * MS) == 'fed'               # silence counted from now
    assert gate.admit(20 * MS, now_ns=20 * MS) == 'accepted'
    assert gate.watchdog(600 * MS) == 'lost'


def test_the_watchdog_counts_on_a_steady_clock_once_fed():
    gate = FeedbackGate(500 * MS, now_ns=0)
    # Before any sample only the node clock counts (a simulated clock not started yet).
    assert gate.watchdog(0, steady_ns=10_000 * MS) == 'fed'
    assert gate.admit(100 * MS, now_ns=100 * MS, steady_ns=7_000 * MS) == 'accepted'
    # The simulated clock stops at 100 ms; steady time goes on.
    assert gate.watchdog(100 * MS, steady_ns=7_400 * MS) == 'fed'
    assert gate.watchdog(100 * MS, steady_ns=7_501 * MS) == 'lost'
    assert gate.silence_ns(100 * MS, steady_ns=7_600 * MS) == 600 * MS
    assert gate.admit(110 * MS, now_ns=110 * MS, steady_ns=7_700 * MS) == 'resumed'

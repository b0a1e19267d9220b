"""Feedback the joint cannot give: beyond its stops, or faster than its top speed."""

from hydro_sdp.core.control.plausibility import FeedbackPlausibility
from hydro_sdp.core.control.safety import top_speeds
from hydro_sdp.core.errors import ConfigurationError, DataError
import numpy as np
import pytest

MS = 1_000_000


@pytest.fixture
def check(j2):
    down, up = top_speeds(j2)
    return FeedbackPlausibility(j2.angle_limits, max(-down, up), margin=1.0)


def test_angles_beyond_the_stops_by_more_than_the_margin_are_refused(check):
    check.check(0, 64.5)                               # 0.9 deg past the stop: a sensor offset
    with pytest.raises(DataError, match=r'angle 5\.72958e\+11 deg lies beyond the end stops '
                                        r'\[-13\.8, 63\.6\] by more than feedback_margin 1'):
        check.check(10 * MS, np.degrees(1e10))
    with pytest.raises(DataError, match='beyond the end stops'):
        check.check(20 * MS, -14.9)


def test_a_jump_faster_than_the_joint_is_refused_once_then_taken(check, j2):
    top = max(-top_speeds(j2)[0], top_speeds(j2)[1])
    assert top == pytest.approx(38.87, rel=1e-3)
    check.check(0, 20.0)
    check.check(10 * MS, 20.0 + 2 * top * 0.01 + 0.99)    # within twice the top speed + 1 deg
    with pytest.raises(DataError, match=r'angle moved -21\.77 deg in 0\.01 s'):
        check.check(20 * MS, 0.0)                        # a plant restarted at 0
    check.check(30 * MS, 0.05)                           # judged against the refused one: taken
    # A single wild sample costs two: it, and the next one judged against it.
    with pytest.raises(DataError):
        check.check(40 * MS, 30.0)
    with pytest.raises(DataError):
        check.check(50 * MS, 0.1)
    check.check(60 * MS, 0.1)


def test_after_a_pause_a_large_change_is_credible(check):
    check.check(0, 0.0)
    check.check(1000 * MS, 60.0)                 # 1 s: 60 deg is less than twice 38.9 deg/s
    check.reset()
    check.check(1010 * MS, -10.0)                # range only after a reset


def test_without_stops_or_speed_nothing_is_checked_and_a_bad_margin_is_refused():
    open_joint = FeedbackPlausibility(None, None, margin=0.0)
    open_joint.check(0, 1e12)
    open_joint.check(1, -1e12)
    for bad in (-1.0, float('nan'), float('inf')):
        with pytest.raises(ConfigurationError, match='feedback_margin'):
            FeedbackPlausibility(None, None, margin=bad)

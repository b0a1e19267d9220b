"""Header stamps to and from integer nanoseconds."""

from builtin_interfaces.msg import Time
from hydro_sdp.ros.conversions import fill_stamp, stamp_to_ns


def test_fill_stamp_splits_nanoseconds_into_seconds_and_remainder():
    stamp = Time()
    fill_stamp(stamp, 1_700_000_000_123_456_789)
    assert (stamp.sec, stamp.nanosec) == (1_700_000_000, 123_456_789)
    assert stamp_to_ns(stamp) == 1_700_000_000_123_456_789


def test_fill_stamp_of_whole_seconds_and_of_zero():
    stamp = Time()
    fill_stamp(stamp, 3_000_000_000)
    assert (stamp.sec, stamp.nanosec) == (3, 0)
    fill_stamp(stamp, 0)
    assert (stamp.sec, stamp.nanosec) == (0, 0)

"""Records cut at the holes a stalled timer leaves in the time stamps."""

from hydro_sdp.core.errors import DataError
from hydro_sdp.core.identification.segmentation import check_record, segment_record
from hydro_sdp.core.model.records import Record, split_at_gaps, split_records
import numpy as np
import pytest

EPOCH = 1_700_000_000.0


def stamped(t, origin=None):
    return Record(t, np.arange(t.size) % 7.0, 0.1 * np.arange(t.size), joint='j',
                  source='bag', origin=origin)


def test_a_record_without_gaps_comes_back_whole():
    record = stamped(EPOCH + 0.01 * np.arange(10))
    pieces = split_at_gaps(record)
    assert pieces.count == 1 and pieces.records[0] is record
    assert pieces.gaps == () and pieces.dropped == 0
    assert pieces.describe() == '1 piece'


def test_a_hole_cuts_the_record_in_two():
    t = EPOCH + 0.01 * np.arange(300)
    t[120:] += 0.39                      # samples 119 and 120 are 0.4 s apart
    record = stamped(t, origin=EPOCH - 2.0)
    pieces = split_at_gaps(record)
    assert pieces.count == 2
    assert [len(piece) for piece in pieces.records] == [120, 180]
    np.testing.assert_array_equal(pieces.records[1].t, t[120:])
    np.testing.assert_array_equal(pieces.records[1].v, record.v[120:])
    np.testing.assert_array_equal(pieces.records[1].y, record.y[120:])
    (gap,) = pieces.gaps
    # Counted from the start of the bag, not in epoch seconds.
    assert gap.t == pytest.approx(3.19) and gap.length == pytest.approx(0.40)
    assert gap.sample == 120
    assert pieces.describe() == '2 pieces (gaps of 0.400 s at 3.190 s)'
    for piece in pieces.records:
        assert piece.joint == 'j' and piece.source == 'bag' and piece.origin == EPOCH - 2.0
        assert check_record(piece) == pytest.approx(0.01)


def test_short_pieces_are_left_out_and_counted():
    t = EPOCH + 0.01 * np.arange(200)
    t[100:] += 1.0
    t[130:] += 1.0                       # a 30-sample island between two holes
    pieces = split_at_gaps(stamped(t))
    assert pieces.count == 2 and len(pieces.gaps) == 2 and pieces.dropped == 30
    assert [len(piece) for piece in pieces.records] == [100, 70]
    assert split_at_gaps(stamped(t), min_samples=10).count == 3
    with pytest.raises(DataError, match='every piece is shorter than 150 samples'):
        split_at_gaps(stamped(t), min_samples=150)


def test_split_records_pools_the_pieces():
    t = 0.01 * np.arange(1, 201)
    holed = t.copy()
    holed[100:] += 0.5
    records, splits = split_records([stamped(t), stamped(holed)])
    assert len(records) == 3 and [split.count for split in splits] == [1, 2]


def test_bad_arguments_are_refused():
    record = stamped(0.01 * np.arange(1, 11))
    with pytest.raises(DataError, match='max_gap'):
        split_at_gaps(record, max_gap=1.0)
    with pytest.raises(DataError, match='min_samples'):
        split_at_gaps(record, min_samples=0)


def test_messages_count_time_from_the_start_of_the_bag():
    t = EPOCH + 0.01 * np.arange(100)
    t[60:] += 1.0
    with pytest.raises(DataError, match=r'gap of 1\.010 s in the time stamps 0\.590 s from '
                                        r'the start'):
        check_record(stamped(t))
    with pytest.raises(DataError, match=r'gap of 1\.010 s in the time stamps 10\.590 s from'):
        check_record(stamped(t, origin=EPOCH - 10.0))
    repeated = t.copy()
    repeated[5] = repeated[4]
    with pytest.raises(DataError, match=r'repeat at sample 5 \(0\.040000 s from the start\)'):
        stamped(repeated)


def test_dropped_segments_say_when_from_the_start_of_the_bag():
    t = EPOCH + 0.01 * np.arange(300)
    v = np.zeros(300)
    v[100:103] = 1.0                     # too short a step to fit
    record = Record(t, v, np.zeros(300), origin=EPOCH - 5.0)
    (dropped,) = segment_record(record, max_delay=5).dropped
    assert dropped.reason.startswith('too short')
    assert dropped.t0 == t[99] and dropped.since_start == pytest.approx(5.99)

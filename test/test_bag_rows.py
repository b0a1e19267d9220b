"""Bulk reading of sqlite3 storage: the same messages, in the same order, as rosbags gives."""

from pathlib import Path

from hydro_sdp.bags import read_bag, write_bag
from hydro_sdp.bags import storage
from hydro_sdp.bags.sqlite_rows import read_rows
from hydro_sdp.core.records import Record
import numpy as np
import pytest
from rosbags.rosbag2 import Reader, StoragePlugin, Writer
from rosbags.typesys import get_typestore, Stores

TYPESTORE = get_typestore(Stores.ROS2_JAZZY)
TYPES = TYPESTORE.types
STATE = 'sensor_msgs/msg/JointState'
FLOAT = 'std_msgs/msg/Float64'


def _state(k):
    return TYPESTORE.serialize_cdr(TYPES[STATE](
        header=TYPES['std_msgs/msg/Header'](
            stamp=TYPES['builtin_interfaces/msg/Time'](sec=1, nanosec=k), frame_id=''),
        name=['j2'], position=np.array([0.001 * k]), velocity=np.zeros(0),
        effort=np.zeros(0)), STATE)


def _float(value):
    return TYPESTORE.serialize_cdr(TYPES[FLOAT](data=float(value)), FLOAT)


def _shuffled_bag(path, rng):
    """Write a bag whose receive times repeat and go back, two topics interleaved."""
    stamps = 10**9 + rng.integers(0, 40, 200) * 10**7
    with Writer(path, version=8, storage_plugin=StoragePlugin.SQLITE3) as writer:
        state = writer.add_connection('/joint_states', STATE, typestore=TYPESTORE)
        command = writer.add_connection('/j2/valve_command', FLOAT, typestore=TYPESTORE)
        for k, stamp in enumerate(stamps.tolist()):
            if k % 3:
                writer.write(state, stamp, _state(k))
            else:
                writer.write(command, stamp, _float(k))
    return path


def _collected(path, monkeypatch, bulk):
    with monkeypatch.context() as patch:
        if not bulk:
            patch.setattr(storage, 'read_rows', lambda reader, wanted: None)
        collected, sources = storage.collect(Path(path), lambda msgtype: True)
    return collected, sources


@pytest.mark.parametrize('source', ['folder', 'file'])
def test_bulk_rows_equal_rosbags_message_order(tmp_path, rng, monkeypatch, source):
    bag = _shuffled_bag(tmp_path / 'bag', rng)
    path = bag if source == 'folder' else next(bag.glob('*.db3'))
    bulk, bulk_sources = _collected(path, monkeypatch, bulk=True)
    single, single_sources = _collected(path, monkeypatch, bulk=False)
    assert bulk_sources == single_sources
    assert bulk.topics == single.topics == {'/joint_states': [STATE, 133],
                                            '/j2/valve_command': [FLOAT, 67]}
    assert bulk.declared == single.declared == 200
    for topic in bulk.topics:
        assert bulk.stamps[topic] == single.stamps[topic]
        assert [bytes(raw) for raw in bulk.raws[topic]] == \
            [bytes(raw) for raw in single.raws[topic]]
    # Ties keep their storage order and the times go back: the order is not trivial.
    assert bulk.stamps['/joint_states'] == sorted(bulk.stamps['/joint_states'])
    assert len(set(bulk.stamps['/joint_states'])) < 133


def test_sqlite_bags_are_not_read_message_by_message(tmp_path, monkeypatch):
    t = 0.01 * np.arange(1, 101)
    record = Record(t, np.sin(t), np.cos(t), joint='j2')
    bag = write_bag(tmp_path / 'bag', [record])

    def refuse(*args, **kwargs):
        raise AssertionError('read message by message')
    monkeypatch.setattr(Reader, 'messages', refuse)
    back = read_bag(bag).record()
    np.testing.assert_array_equal(back.v, record.v)
    np.testing.assert_allclose(back.y, record.y, atol=1e-12)


def test_mcap_bags_are_left_to_rosbags(tmp_path):
    t = 0.01 * np.arange(1, 11)
    bag = write_bag(tmp_path / 'bag', [Record(t, t, t, joint='j2')], storage='mcap')
    with Reader(bag) as reader:
        assert read_rows(reader, reader.connections) is None
    assert read_bag(bag).record().y.size == 10

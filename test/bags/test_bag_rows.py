"""Bulk reading of sqlite3 storage: the same messages, in the same order, as rosbags gives."""

from pathlib import Path

from hydro_sdp.bags import read_bag, write_bag
from hydro_sdp.bags import storage
from hydro_sdp.bags.plain_sqlite import read_plain
from hydro_sdp.bags.sqlite_rows import read_rows
from hydro_sdp.core.errors import BagFormatError, BagReadError
from hydro_sdp.core.model.records import Record
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


def _collected(path, monkeypatch, mode):
    """Collect every message: without rosbags, rosbags with bulk rows, or message by message."""
    with monkeypatch.context() as patch:
        if mode != 'plain':
            patch.setattr(storage, 'read_plain', lambda source, keep: None)
        if mode == 'messages':
            patch.setattr(storage, 'read_rows', lambda reader, wanted: None)
        return storage.collect(Path(path), lambda msgtype: True)


@pytest.mark.parametrize(('source', 'mode'), [('folder', 'plain'), ('folder', 'bulk'),
                                              ('file', 'bulk')])
def test_bulk_rows_equal_rosbags_message_order(tmp_path, rng, monkeypatch, source, mode):
    bag = _shuffled_bag(tmp_path / 'bag', rng)
    path = bag if source == 'folder' else next(bag.glob('*.db3'))
    bulk, bulk_sources = _collected(path, monkeypatch, mode)
    single, single_sources = _collected(path, monkeypatch, 'messages')
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


def _bag(tmp_path, storage='sqlite3'):
    t = 0.01 * np.arange(1, 101)
    record = Record(t, np.sin(t), np.cos(t), joint='j2')
    return record, write_bag(tmp_path / 'bag', [record], storage=storage)


def _refuse(*args, **kwargs):
    raise AssertionError('opened with rosbags')


def test_plain_sqlite_folders_are_read_without_rosbags(tmp_path, monkeypatch):
    record, bag = _bag(tmp_path)
    monkeypatch.setattr(Reader, 'open', _refuse)
    back = read_bag(bag).record()
    np.testing.assert_array_equal(back.v, record.v)
    np.testing.assert_allclose(back.y, record.y, atol=1e-12)


def test_storage_files_are_read_in_bulk_through_rosbags(tmp_path, monkeypatch):
    record, bag = _bag(tmp_path)
    monkeypatch.setattr(Reader, 'messages', _refuse)
    back = read_bag(next(bag.glob('*.db3'))).record()
    np.testing.assert_array_equal(back.v, record.v)


@pytest.mark.parametrize('change', ['qos', 'version', 'serialization'])
def test_other_folders_are_left_to_rosbags(tmp_path, change):
    _, bag = _bag(tmp_path)
    metadata = bag / 'metadata.yaml'
    text = metadata.read_text()
    if change == 'qos':       # rosbags may still read both texts as the same QoS
        text = text.replace("offered_qos_profiles: ''", 'offered_qos_profiles: "[]"')
    elif change == 'version':
        text = text.replace('version: 8', 'version: 10')
    else:
        text = text.replace('serialization_format: cdr', 'serialization_format: xcdr', 1)
    assert text != metadata.read_text()
    metadata.write_text(text)
    assert read_plain(bag, lambda msgtype: True) is None
    if change == 'qos':
        assert read_bag(bag).record().y.size == 100
    else:
        with pytest.raises(BagFormatError if change == 'serialization' else BagReadError):
            read_bag(bag)


def test_mcap_bags_are_left_to_rosbags(tmp_path):
    _, bag = _bag(tmp_path, 'mcap')
    assert read_plain(bag, lambda msgtype: True) is None
    with Reader(bag) as reader:
        assert read_rows(reader, reader.connections) is None
    assert read_bag(bag).record().y.size == 100

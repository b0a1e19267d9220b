"""The sqlite3 reader gives the same topics, messages and order as rosbags' Reader."""

from pathlib import Path

from conftest import FIXTURES
from hydro_sdp.bags import read_bag, write_bag
from hydro_sdp.bags import storage
from hydro_sdp.bags.sqlite_reader import read_sqlite
from hydro_sdp.core.errors import BagFormatError, BagReadError
from hydro_sdp.core.model.records import Record
import numpy as np
import pytest
from rosbags.interfaces import (
    Qos, QosDurability, QosHistory, QosLiveliness, QosReliability, QosTime)
from rosbags.rosbag2 import Reader, StoragePlugin, Writer
from rosbags.typesys import get_typestore, Stores

TYPESTORE = get_typestore(Stores.ROS2_JAZZY)
TYPES = TYPESTORE.types
STATE = 'sensor_msgs/msg/JointState'
FLOAT = 'std_msgs/msg/Float64'
FOREVER = QosTime(9223372036, 854775807)
#: What ``ros2 bag record`` on Jazzy records for a default publisher.
JAZZY_QOS = Qos(QosHistory.UNKNOWN, 0, QosReliability.RELIABLE, QosDurability.VOLATILE,
                FOREVER, FOREVER, QosLiveliness.AUTOMATIC, FOREVER, False)


def _state(k):
    return TYPESTORE.serialize_cdr(TYPES[STATE](
        header=TYPES['std_msgs/msg/Header'](
            stamp=TYPES['builtin_interfaces/msg/Time'](sec=1, nanosec=k), frame_id=''),
        name=['j2'], position=np.array([0.001 * k]), velocity=np.zeros(0),
        effort=np.zeros(0)), STATE)


def _float(value):
    return TYPESTORE.serialize_cdr(TYPES[FLOAT](data=float(value)), FLOAT)


def _shuffled_bag(path, rng, version=8, qos=()):
    """Write a bag whose receive times repeat and go back, two topics interleaved."""
    stamps = 10**9 + rng.integers(0, 40, 200) * 10**7
    with Writer(path, version=version, storage_plugin=StoragePlugin.SQLITE3) as writer:
        state = writer.add_connection('/joint_states', STATE, typestore=TYPESTORE,
                                      offered_qos_profiles=qos)
        command = writer.add_connection('/j2/valve_command', FLOAT, typestore=TYPESTORE,
                                        offered_qos_profiles=qos)
        for k, stamp in enumerate(stamps.tolist()):
            if k % 3:
                writer.write(state, stamp, _state(k))
            else:
                writer.write(command, stamp, _float(k))
    return path


def _collected(path, monkeypatch, reader):
    """Collect every message with the sqlite3 reader, or with rosbags' Reader only."""
    with monkeypatch.context() as patch:
        if reader == 'rosbags':
            patch.setattr(storage, 'read_sqlite', lambda source, keep: None)
        else:
            patch.setattr(Reader, 'open', _refuse)
        return storage.collect(Path(path), lambda msgtype: True)


def _refuse(*args, **kwargs):
    raise AssertionError('opened with rosbags')


def _assert_same(path, monkeypatch):
    ours, our_sources = _collected(path, monkeypatch, 'sqlite')
    theirs, their_sources = _collected(path, monkeypatch, 'rosbags')
    assert our_sources == their_sources
    assert ours.topics == theirs.topics
    assert ours.declared == theirs.declared
    assert ours.stamps == theirs.stamps
    assert {topic: [bytes(raw) for raw in raws] for topic, raws in ours.raws.items()} == \
        {topic: [bytes(raw) for raw in raws] for topic, raws in theirs.raws.items()}
    return ours


@pytest.mark.parametrize('source', ['folder', 'file'])
@pytest.mark.parametrize('metadata', ['version 8', 'Jazzy QoS lists'])
def test_the_same_messages_in_the_same_order_as_rosbags(tmp_path, rng, monkeypatch, source,
                                                        metadata):
    jazzy = metadata == 'Jazzy QoS lists'
    bag = _shuffled_bag(tmp_path / 'bag', rng, 9 if jazzy else 8, [JAZZY_QOS] if jazzy else [])
    if jazzy:
        text = (bag / 'metadata.yaml').read_text()
        assert 'version: 9' in text and '        history: unknown' in text
    collected = _assert_same(bag if source == 'folder' else next(bag.glob('*.db3')),
                             monkeypatch)
    assert collected.topics == {'/joint_states': [STATE, 133], '/j2/valve_command': [FLOAT, 67]}
    assert collected.declared == 200
    # Ties keep their storage order and the times go back: the order is not trivial.
    assert collected.stamps['/joint_states'] == sorted(collected.stamps['/joint_states'])
    assert len(set(collected.stamps['/joint_states'])) < 133


def _bag(tmp_path, storage='sqlite3'):
    t = 0.01 * np.arange(1, 101)
    record = Record(t, np.sin(t), np.cos(t), joint='j2')
    return record, write_bag(tmp_path / 'bag', [record], storage=storage)


def test_bags_this_package_writes_are_read_as_rosbags_reads_them(tmp_path, monkeypatch):
    record, bag = _bag(tmp_path)
    for source in (bag, next(bag.glob('*.db3'))):
        _assert_same(source, monkeypatch)
    monkeypatch.setattr(Reader, 'open', _refuse)
    back = read_bag(bag).record()
    np.testing.assert_array_equal(back.v, record.v)
    np.testing.assert_allclose(back.y, record.y, atol=1e-12)


def _sqlite_fixtures():
    if not FIXTURES.is_dir():  # pragma: no cover - the fixtures live beside the repository
        return []
    folders = {p.parent for p in FIXTURES.rglob('metadata.yaml')
               if 'sqlite3' in p.read_text()}
    return sorted(folders | set(FIXTURES.rglob('*.db3')))


@pytest.mark.skipif(not FIXTURES.is_dir(), reason=f'no rosbag2 fixtures at {FIXTURES}')
@pytest.mark.parametrize('bag', _sqlite_fixtures(),
                         ids=lambda p: str(p.relative_to(FIXTURES)))
def test_rosbag2_fixtures_are_read_as_rosbags_reads_them(bag, monkeypatch):
    if bag.name == 'wrong_rmw_test':    # left to rosbags, which says what it refuses
        assert read_sqlite(bag, lambda msgtype: True) is None
        with pytest.raises(BagFormatError, match='wrong_format'):
            storage.collect(bag, lambda msgtype: True)
        return
    _assert_same(bag, monkeypatch)


@pytest.mark.parametrize('change', ['version', 'serialization'])
def test_other_folders_are_left_to_rosbags(tmp_path, change):
    _, bag = _bag(tmp_path)
    metadata = bag / 'metadata.yaml'
    text = metadata.read_text()
    if change == 'version':
        text = text.replace('version: 8', 'version: 10')
    else:
        text = text.replace('serialization_format: cdr', 'serialization_format: xcdr', 1)
    assert text != metadata.read_text()
    metadata.write_text(text)
    assert read_sqlite(bag, lambda msgtype: True) is None
    with pytest.raises(BagFormatError if change == 'serialization' else BagReadError):
        read_bag(bag)


def test_qos_of_another_spelling_is_judged_as_rosbags_judges_it(tmp_path, monkeypatch):
    _, bag = _bag(tmp_path)
    metadata = bag / 'metadata.yaml'
    metadata.write_text(metadata.read_text().replace("offered_qos_profiles: ''",
                                                     'offered_qos_profiles: "[]"'))
    assert _assert_same(bag, monkeypatch).kept == 200


def test_mcap_bags_are_left_to_rosbags(tmp_path):
    _, bag = _bag(tmp_path, 'mcap')
    assert read_sqlite(bag, lambda msgtype: True) is None
    assert read_sqlite(next(bag.glob('*.mcap')), lambda msgtype: True) is None
    assert read_bag(bag).record().y.size == 100

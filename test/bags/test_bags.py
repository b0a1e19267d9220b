"""rosbag2 reading and writing: round trips, alignment, the bulk codec and bad bags."""

from hydro_sdp.bags import (
    EmptyBagError, inspect_bag, raw_messages, read_bag, read_record, write_bag)
from hydro_sdp.bags.cdr import (
    decode_float64, decode_joint_states, encode_float64, encode_joint_states)
from hydro_sdp.core.errors import (
    BagFormatError, BagNotFoundError, BagReadError, DataError, JointNotFoundError,
    TopicNotFoundError)
from hydro_sdp.core.model.records import Record
import numpy as np
import pytest
from rosbags.rosbag2 import StoragePlugin, Writer
from rosbags.typesys import get_typestore, Stores

TYPESTORE = get_typestore(Stores.ROS2_JAZZY)
TYPES = TYPESTORE.types


def _records(rng, n=500):
    t = 1.5 + np.arange(n) * 0.01
    return [Record(t, rng.uniform(-5, 5, n), rng.uniform(-10, 60, n), joint='boom'),
            Record(t, rng.uniform(-100, 100, n), rng.uniform(-90, 0, n), joint='dipper')]


@pytest.mark.parametrize('storage', ['sqlite3', 'mcap'])
def test_round_trip_of_several_joints(tmp_path, rng, storage):
    records = _records(rng)
    setpoint = np.linspace(0.0, 30.0, 500)
    bag = write_bag(tmp_path / 'bag', records, storage=storage, setpoints={'boom': setpoint})
    data = read_bag(bag)
    assert data.names == ('boom', 'dipper')
    assert set(data.floats) == {'/boom/valve_command', '/dipper/valve_command', '/boom/setpoint'}
    np.testing.assert_allclose(np.degrees(data.floats['/boom/setpoint'].data), setpoint,
                               atol=1e-12)
    for record in records:
        back = data.record(record.joint)
        # Times count from the whole second before the bag's first message.
        assert data.start == 1_000_000_000
        np.testing.assert_allclose(back.t + data.start * 1e-9, record.t, atol=1e-9)
        np.testing.assert_array_equal(back.v, record.v)
        np.testing.assert_allclose(back.y, record.y, atol=1e-12)
        assert back.joint == record.joint
    info = inspect_bag(bag)
    assert info.message_count == 4 * 500


def test_the_only_joint_and_command_are_the_defaults(tmp_path, rng):
    record = _records(rng)[0]
    bag = write_bag(tmp_path / 'bag', [record])
    back = read_record(bag)
    assert back.joint == 'boom'
    np.testing.assert_array_equal(back.v, record.v)


def _write_raw(path, messages, storage='sqlite3'):
    """Write (topic, msgtype, stamp_ns, message object or raw bytes) tuples."""
    plugin = StoragePlugin.MCAP if storage == 'mcap' else StoragePlugin.SQLITE3
    with Writer(path, version=8, storage_plugin=plugin) as writer:
        connections = {}
        for topic, msgtype, stamp, message in messages:
            if topic not in connections:
                connections[topic] = writer.add_connection(topic, msgtype, typestore=TYPESTORE)
            raw = message if isinstance(message, bytes) else TYPESTORE.serialize_cdr(
                message, msgtype)
            writer.write(connections[topic], stamp, raw)
    return path


def _joint_state(stamp_ns, names, positions, frame_id=''):
    return TYPES['sensor_msgs/msg/JointState'](
        header=TYPES['std_msgs/msg/Header'](
            stamp=TYPES['builtin_interfaces/msg/Time'](
                sec=stamp_ns // 10**9, nanosec=stamp_ns % 10**9),
            frame_id=frame_id),
        name=list(names), position=np.asarray(positions, dtype=float),
        velocity=np.zeros(0), effort=np.zeros(0))


def _float(value):
    return TYPES['std_msgs/msg/Float64'](data=float(value))


def test_commands_are_held_between_messages(tmp_path):
    # Commands every 0.05 s, angles every 0.01 s: v_k is the last command sent before t_k,
    # and angles with no earlier command are dropped.
    messages = [('/joint_states', 'sensor_msgs/msg/JointState', k * 10**7,
                 _joint_state(k * 10**7, ['j2'], [0.001 * k])) for k in range(20)]
    messages += [('/j2/valve_command', 'std_msgs/msg/Float64', (2 + 5 * k) * 10**7,
                  _float(k + 1.0)) for k in range(4)]
    bag = _write_raw(tmp_path / 'bag', messages)
    record = read_record(bag)
    np.testing.assert_allclose(record.t, np.arange(3, 20) * 0.01)
    np.testing.assert_array_equal(record.v, [1.0] * 5 + [2.0] * 5 + [3.0] * 5 + [4.0] * 2)
    np.testing.assert_allclose(record.y, np.degrees(0.001 * np.arange(3, 20)))


def test_receive_time_is_used_when_stamps_are_unset(tmp_path):
    messages = [('/joint_states', 'sensor_msgs/msg/JointState', 10**9 + k * 10**7,
                 _joint_state(0, ['j2'], [0.0])) for k in range(5)]
    messages += [('/j2/valve_command', 'std_msgs/msg/Float64', 10**9 - 1, _float(1.0))]
    record = read_record(_write_raw(tmp_path / 'bag', messages))
    np.testing.assert_allclose(record.t, 1.0 + np.arange(5) * 0.01)


def test_bulk_decoder_agrees_with_rosbags(rng):
    messages = []
    for k in range(300):
        names = ['a', 'b'] if k % 7 else ['b', 'c', 'a']       # layouts change mid-stream
        frame = 'base' if k % 11 else 'arm_link'
        message = _joint_state(10**9 * k + 17, names, rng.normal(size=len(names)), frame)
        little = k % 13 != 0                                   # some big-endian messages
        messages.append((message, bytes(TYPESTORE.serialize_cdr(
            message, 'sensor_msgs/msg/JointState', little_endian=little))))
    decoded = decode_joint_states([raw for _, raw in messages])
    assert decoded.names == ('a', 'b', 'c')
    for k, (message, raw) in enumerate(messages):
        back = TYPESTORE.deserialize_cdr(raw, 'sensor_msgs/msg/JointState')
        assert decoded.stamps[k] == back.header.stamp.sec * 10**9 + back.header.stamp.nanosec
        for name, value in zip(back.name, back.position):
            column = decoded.names.index(name)
            assert decoded.positions[k, column] == value
            assert decoded.present[k, column]
        assert decoded.present[k].sum() == len(back.name)
    values = rng.normal(size=50)
    raws = [bytes(TYPESTORE.serialize_cdr(_float(x), 'std_msgs/msg/Float64',
                                          little_endian=bool(i % 2)))
            for i, x in enumerate(values)]
    np.testing.assert_array_equal(decode_float64(raws), values)


@pytest.mark.parametrize('storage', ['sqlite3', 'mcap'])
def test_codec_agrees_with_rosbags_on_the_bags_this_package_writes(tmp_path, rng, storage):
    records = _records(rng, 50)
    bag = write_bag(tmp_path / 'bag', records, storage=storage, start=1_760_000_000 * 10**9,
                    setpoints={'boom': rng.uniform(-10, 60, 50)})
    messages = raw_messages(bag)
    states = [raw for _, msgtype, _, raw in messages if msgtype == 'sensor_msgs/msg/JointState']
    floats = [raw for _, msgtype, _, raw in messages if msgtype == 'std_msgs/msg/Float64']
    assert len(states) == 50 and len(floats) == 150
    decoded = decode_joint_states(states)
    theirs = [TYPESTORE.deserialize_cdr(raw, 'sensor_msgs/msg/JointState') for raw in states]
    assert decoded.names == tuple(theirs[0].name) == ('boom', 'dipper')
    np.testing.assert_array_equal(decoded.positions, [m.position for m in theirs])
    np.testing.assert_array_equal(
        decoded.stamps, [m.header.stamp.sec * 10**9 + m.header.stamp.nanosec for m in theirs])
    values = [TYPESTORE.deserialize_cdr(raw, 'std_msgs/msg/Float64').data for raw in floats]
    np.testing.assert_array_equal(decode_float64(floats), values)
    # Encoding: byte for byte what rosbags serialises.
    assert encode_joint_states(states[0], decoded.stamps, decoded.positions) == \
        [bytes(TYPESTORE.serialize_cdr(m, 'sensor_msgs/msg/JointState')) for m in theirs]
    assert encode_float64(np.asarray(values)) == floats


def test_joints_that_come_and_go(tmp_path):
    messages = []
    for k in range(10):
        names = ['j1', 'j2'] if k % 2 else ['j1']
        messages.append(('/joint_states', 'sensor_msgs/msg/JointState', k * 10**7,
                         _joint_state(k * 10**7, names, [0.1] * len(names))))
    messages.append(('/j2/valve_command', 'std_msgs/msg/Float64', 0, _float(0.5)))
    data = read_bag(_write_raw(tmp_path / 'bag', messages))
    record = data.record('j2')
    assert len(record) == 5
    with pytest.raises(JointNotFoundError, match='choose one with --joint'):
        data.record()


def test_missing_joint_and_topics(tmp_path, rng):
    bag = write_bag(tmp_path / 'bag', _records(rng))
    data = read_bag(bag)
    with pytest.raises(JointNotFoundError, match="joint 'stick' is not in /joint_states"):
        data.record('stick')
    with pytest.raises(TopicNotFoundError, match='no topic /boom/cmd'):
        data.record('boom', '/boom/cmd')
    with pytest.raises(TopicNotFoundError, match='JointState topic /states'):
        read_bag(bag, state_topic='/states')


def test_command_topic_of_another_type(tmp_path):
    messages = [('/joint_states', 'sensor_msgs/msg/JointState', k * 10**7,
                 _joint_state(k * 10**7, ['j2'], [0.0])) for k in range(5)]
    messages.append(('/j2/valve_command', 'std_msgs/msg/Float32', 0,
                     TYPES['std_msgs/msg/Float32'](data=1.0)))
    data = read_bag(_write_raw(tmp_path / 'bag', messages))
    with pytest.raises(TopicNotFoundError, match='no std_msgs/msg/Float64 topic ending in'):
        data.record()
    with pytest.raises(TopicNotFoundError, match='is std_msgs/msg/Float32, not'):
        data.record(command_topic='/j2/valve_command')


@pytest.mark.parametrize(('stamps', 'message'), [
    ([0, 1, 1, 2], 'time stamps repeat at sample 2'),
    ([0, 2, 1, 3], 'time stamps go backwards at sample 2'),
])
def test_stamps_that_repeat_or_go_back(tmp_path, stamps, message):
    messages = [('/joint_states', 'sensor_msgs/msg/JointState', k * 10**7,
                 _joint_state(s * 10**7 + 1, ['j2'], [0.0])) for k, s in enumerate(stamps)]
    messages.append(('/j2/valve_command', 'std_msgs/msg/Float64', 0, _float(0.5)))
    with pytest.raises(DataError, match=message):
        read_record(_write_raw(tmp_path / 'bag', messages))


def test_nan_samples_are_refused(tmp_path):
    messages = [('/joint_states', 'sensor_msgs/msg/JointState', k * 10**7,
                 _joint_state(k * 10**7 + 1, ['j2'], [np.nan if k == 3 else 0.0]))
                for k in range(6)]
    messages.append(('/j2/valve_command', 'std_msgs/msg/Float64', 0, _float(0.5)))
    with pytest.raises(DataError, match='1 angle samples are NaN or infinite'):
        read_record(_write_raw(tmp_path / 'bag', messages))


@pytest.mark.parametrize('storage', ['sqlite3', 'mcap'])
def test_truncated_storage_file(tmp_path, rng, storage):
    bag = write_bag(tmp_path / 'bag', _records(rng, 5000), storage=storage)
    storage_file = next(p for p in bag.iterdir() if p.suffix in ('.db3', '.mcap'))
    storage_file.write_bytes(storage_file.read_bytes()[:storage_file.stat().st_size // 2])
    with pytest.raises(BagReadError, match='cannot read bag'):
        read_bag(bag)


def test_missing_and_empty_paths(tmp_path):
    with pytest.raises(BagNotFoundError, match='no such bag'):
        read_bag(tmp_path / 'absent')
    with pytest.raises(BagNotFoundError, match='no metadata.yaml and no .db3 or .mcap'):
        read_bag(tmp_path)
    (tmp_path / 'notes.txt').write_text('hello')
    with pytest.raises(BagFormatError, match='not a rosbag2 storage file'):
        read_bag(tmp_path / 'notes.txt')
    empty = _write_raw(tmp_path / 'empty', [])
    with pytest.raises(EmptyBagError, match='holds no messages'):
        read_bag(empty)


def test_write_refuses_misaligned_records(tmp_path, rng):
    a, b = _records(rng)
    shifted = Record(a.t + 0.001, a.v, a.y, joint='stick')
    with pytest.raises(DataError, match='share their time stamps'):
        write_bag(tmp_path / 'bag', [a, shifted])
    with pytest.raises(DataError, match='distinct'):
        write_bag(tmp_path / 'bag', [a, a])
    assert not (tmp_path / 'bag').exists()


def test_failed_write_leaves_the_old_bag(tmp_path, rng, monkeypatch):
    records = _records(rng)
    bag = write_bag(tmp_path / 'bag', records[:1])

    def explode(self, connection, timestamp, data):
        raise KeyboardInterrupt

    monkeypatch.setattr(Writer, 'write', explode)
    with pytest.raises(KeyboardInterrupt):
        write_bag(tmp_path / 'bag', records)
    monkeypatch.undo()
    assert read_bag(bag).names == ('boom',)
    assert sorted(p.name for p in tmp_path.iterdir()) == ['bag']

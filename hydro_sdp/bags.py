"""
Reading and writing rosbag2 bags (sqlite3 and mcap) with ``rosbags``.

Bags hold ``/joint_states`` (``sensor_msgs/msg/JointState``, radians) and one
``std_msgs/msg/Float64`` valve command topic per joint (docs/interfaces.md
section 2). :func:`read_bag` turns a bag into arrays; :meth:`BagData.record`
picks one joint and its command and returns a :class:`~hydro_sdp.core.records.Record`
in degrees. Anything that cannot be used is refused with a typed error that
says why: a missing path, an empty bag, an unknown serialisation, a corrupt
storage file, a missing topic or joint.

Bags written by older tools sometimes read empty through their folder although
their storage files hold messages (the QoS text in ``metadata.yaml`` differs
from the storage's); such bags, and split bags without ``metadata.yaml``, are
read from their storage files directly.

"""

from __future__ import annotations

from dataclasses import dataclass
import os
from pathlib import Path
from typing import Callable, Iterable, Mapping, Sequence

from hydro_sdp.cdr import decode_float64, decode_joint_states, encode_float64, encode_joint_states
from hydro_sdp.core.arrays import FloatArray
from hydro_sdp.core.errors import (
    BagError, BagFormatError, BagNotFoundError, BagReadError, DataError, JointNotFoundError,
    TopicNotFoundError)
from hydro_sdp.core.records import Record
from hydro_sdp.files import atomic_directory
import numpy as np

JOINT_STATE = 'sensor_msgs/msg/JointState'
FLOAT64 = 'std_msgs/msg/Float64'
STORAGE_SUFFIXES = ('.db3', '.mcap')
#: Storage plugins by the names users type.
STORAGES = ('sqlite3', 'mcap')

Progress = Callable[[int], None]


class EmptyBagError(BagError, ValueError):
    """The bag holds no messages."""


@dataclass(frozen=True)
class TopicInfo:
    """
    One topic of a bag.

    Parameters
    ----------
    name : str
        Topic name.
    msgtype : str
        Message type, e.g. ``sensor_msgs/msg/JointState``.
    count : int
        Messages read from the storage.

    """

    name: str
    msgtype: str
    count: int


@dataclass(frozen=True)
class BagInfo:
    """
    What a bag holds.

    Parameters
    ----------
    path : Path
        The bag as given.
    sources : tuple[Path, ...]
        What was opened: the bag folder, or its storage files.
    topics : tuple[TopicInfo, ...]
        Topics with their message counts.

    """

    path: Path
    sources: tuple[Path, ...]
    topics: tuple[TopicInfo, ...]

    @property
    def message_count(self) -> int:
        """Total messages read."""
        return sum(topic.count for topic in self.topics)

    def describe(self) -> str:
        """One-line list of the topics, for messages."""
        if not self.topics:
            return 'no topics'
        return ', '.join(f'{t.name} [{t.msgtype}]' for t in self.topics)


def _normalise_type(msgtype: str) -> str:
    # Old bags spell types without the '/msg/' part (test_msgs/BasicTypes).
    parts = msgtype.split('/')
    return f'{parts[0]}/msg/{parts[1]}' if len(parts) == 2 else msgtype


def _sources(path: Path) -> tuple[list[Path], bool]:
    """Return what to open, and whether it is a folder with metadata."""
    if not path.exists():
        raise BagNotFoundError(f'{path}: no such bag')
    if path.is_file():
        if path.name == 'metadata.yaml':
            return _sources(path.parent)
        if path.suffix not in STORAGE_SUFFIXES:
            raise BagFormatError(f'{path}: not a rosbag2 storage file (.db3 or .mcap)')
        return [path], False
    if (path / 'metadata.yaml').is_file():
        return [path], True
    files = _storage_files(path)
    if not files:
        raise BagNotFoundError(f'{path}: no metadata.yaml and no .db3 or .mcap storage file')
    return files, False


def _storage_files(folder: Path) -> list[Path]:
    return sorted(p for p in folder.iterdir() if p.is_file() and p.suffix in STORAGE_SUFFIXES)


@dataclass
class _Collected:
    topics: dict[str, list]  # name -> [msgtype, count]
    stamps: dict[str, list[int]]
    raws: dict[str, list[bytes]]
    declared: int = 0

    @property
    def kept(self) -> int:
        return sum(len(raws) for raws in self.raws.values())


def _collect_from(sources: Iterable[Path], keep: Callable[[str], bool],
                  progress: Progress | None) -> _Collected:
    from rosbags.rosbag2 import Reader, ReaderError

    collected = _Collected({}, {}, {})
    for source in sources:
        try:
            with Reader(source) as reader:
                collected.declared += reader.message_count
                for connection in reader.connections:
                    msgtype = _normalise_type(connection.msgtype)
                    collected.topics.setdefault(connection.topic, [msgtype, 0])
                wanted = [c for c in reader.connections
                          if keep(_normalise_type(c.msgtype))]
                for connection, timestamp, raw in reader.messages(connections=wanted):
                    topic = connection.topic
                    collected.topics[topic][1] += 1
                    collected.stamps.setdefault(topic, []).append(timestamp)
                    collected.raws.setdefault(topic, []).append(raw)
                    if progress is not None and collected.kept % 50_000 == 0:
                        progress(collected.kept)
        except ReaderError as error:
            text = str(error)
            if 'format' in text.lower() and 'not supported' in text.lower():
                raise BagFormatError(f'{source}: {text}') from None
            raise BagReadError(f'{source}: cannot read bag: {text}') from None
        except BagError:
            raise
        except FileNotFoundError as error:
            raise BagNotFoundError(f'{source}: {error}') from None
        except Exception as error:  # noqa: B902 - storage libraries raise anything
            raise BagReadError(
                f'{source}: cannot read bag ({type(error).__name__}: {error})') from None
    return collected


def _collect(path: Path, keep: Callable[[str], bool],
             progress: Progress | None = None) -> tuple[_Collected, list[Path]]:
    sources, is_folder = _sources(path)
    collected = _collect_from(sources, keep, progress)
    if is_folder and collected.kept == 0:
        files = _storage_files(path)
        if files:
            direct = _collect_from(files, keep, progress)
            if direct.kept > 0:
                return direct, files
    return collected, sources


def raw_messages(path: str | os.PathLike[str]) -> list[tuple[str, str, int, bytes]]:
    """
    Every message of a bag as ``(topic, msgtype, timestamp_ns, raw CDR bytes)``.

    Parameters
    ----------
    path : str or PathLike
        The bag.

    Returns
    -------
    list of tuple
        In the order the storage returns them (by time).

    """
    collected, _ = _collect(Path(path), lambda msgtype: True)
    out = []
    for topic, raws in collected.raws.items():
        msgtype = collected.topics[topic][0]
        out.extend((topic, msgtype, stamp, bytes(raw))
                   for stamp, raw in zip(collected.stamps[topic], raws))
    return sorted(out, key=lambda message: message[2])


def inspect_bag(path: str | os.PathLike[str]) -> BagInfo:
    """
    List a bag's topics and count its messages.

    Parameters
    ----------
    path : str or PathLike
        Bag folder, storage file, or folder of split storage files.

    Returns
    -------
    BagInfo
        Topics with the number of messages actually read.

    """
    bag = Path(path)
    collected, sources = _collect(bag, lambda msgtype: True)
    topics = tuple(TopicInfo(name, msgtype, count)
                   for name, (msgtype, count) in sorted(collected.topics.items()))
    return BagInfo(bag, tuple(sources), topics)


@dataclass(frozen=True, eq=False)
class Series:
    """
    Samples of one ``std_msgs/msg/Float64`` topic.

    Parameters
    ----------
    topic : str
        Topic name.
    t : FloatArray
        Receive times, s.
    data : FloatArray
        Values.

    """

    topic: str
    t: FloatArray
    data: FloatArray


@dataclass(frozen=True, eq=False)
class BagData:
    """
    JointState and Float64 content of a bag, ready to become records.

    Parameters
    ----------
    path : Path
        The bag.
    state_topic : str
        The JointState topic read.
    t : FloatArray
        Time of each JointState message, s (``header.stamp``, or the receive
        time where the publisher left the stamps at zero).
    names : tuple[str, ...]
        Joint names.
    positions : FloatArray
        ``(messages, joints)`` positions in radians (NaN where a message lacks a joint).
    present : numpy.ndarray
        Whether each message named each joint.
    floats : Mapping[str, Series]
        Every Float64 topic.
    info : BagInfo
        The bag's topics.

    """

    path: Path
    state_topic: str
    t: FloatArray
    names: tuple[str, ...]
    positions: FloatArray
    present: np.ndarray
    floats: Mapping[str, Series]
    info: BagInfo

    def angles(self, joint: str) -> tuple[FloatArray, FloatArray]:
        """
        Time and angle (degrees) of the messages that name ``joint``.

        Parameters
        ----------
        joint : str
            Joint name.

        Returns
        -------
        tuple of FloatArray
            ``(t, y)``.

        """
        if joint not in self.names:
            joints = ', '.join(self.names)
            raise JointNotFoundError(f'{self.path}: joint {joint!r} is not in {self.state_topic} '
                                     f'(joints: {joints})')
        column = self.names.index(joint)
        mask = self.present[:, column]
        return self.t[mask], np.degrees(self.positions[mask, column])

    def choose_joint(self, joint: str | None) -> str:
        """Return ``joint``, or the only joint of the bag when it is ``None``."""
        if joint is not None:
            if joint not in self.names:
                raise JointNotFoundError(f'{self.path}: joint {joint!r} is not in '
                                         f"{self.state_topic} (joints: {', '.join(self.names)})")
            return joint
        if len(self.names) != 1:
            raise JointNotFoundError(f"{self.path}: the bag has joints {', '.join(self.names)}; "
                                     'choose one with --joint')
        return self.names[0]

    def command_topic(self, joint: str, topic: str | None = None) -> str:
        """
        Find the Float64 command topic of ``joint``.

        Parameters
        ----------
        joint : str
            Joint name, used to choose among several ``valve_command`` topics.
        topic : str or None
            Topic asked for by the user; checked to be a Float64 topic of the bag.

        Returns
        -------
        str
            Topic name.

        """
        if topic is not None:
            if topic in self.floats:
                return topic
            for info in self.info.topics:
                if info.name == topic:
                    raise TopicNotFoundError(
                        f'{self.path}: topic {topic} is {info.msgtype}, not {FLOAT64}')
            raise TopicNotFoundError(f'{self.path}: no topic {topic} '
                                     f'(topics: {self.info.describe()})')
        candidates = [name for name in self.floats if name.endswith('valve_command')]
        if len(candidates) > 1:
            own = [name for name in candidates
                   if name.rstrip('/').endswith(f'{joint}/valve_command')]
            candidates = own if len(own) == 1 else candidates
        if len(candidates) == 1:
            return candidates[0]
        if not candidates:
            raise TopicNotFoundError(f'{self.path}: no {FLOAT64} topic ending in valve_command '
                                     f'(topics: {self.info.describe()})')
        raise TopicNotFoundError(f"{self.path}: several command topics ({', '.join(candidates)}); "
                                 'choose one with --command-topic')

    def record(self, joint: str | None = None, command_topic: str | None = None) -> Record:
        """
        One joint's angle with the command in force before each angle sample.

        ``v_k`` is the last command received before ``t_k`` (zero-order hold):
        the one a plant applies over the interval ending at ``t_k``. Angle
        samples without an earlier command are dropped.

        Parameters
        ----------
        joint : str or None
            Joint name; default: the only joint in the bag.
        command_topic : str or None
            Float64 command topic; default: the only topic ending in ``valve_command``.

        Returns
        -------
        Record
            ``t`` (s), ``v`` (input units), ``y`` (degrees).

        """
        joint = self.choose_joint(joint)
        topic = self.command_topic(joint, command_topic)
        t, y = self.angles(joint)
        series = self.floats[topic]
        if series.t.size == 0:
            raise DataError(f'{self.path}: command topic {topic} has no messages')
        order = np.argsort(series.t, kind='stable')
        command_t, command = series.t[order], series.data[order]
        index = np.searchsorted(command_t, t, side='left') - 1
        keep = index >= 0
        if not keep.any():
            raise DataError(f'{self.path}: no {topic} message arrives before the last '
                            f'{self.state_topic} sample')
        return Record(t[keep], command[index[keep]], y[keep], joint=joint, source=str(self.path))


def read_bag(path: str | os.PathLike[str], *, state_topic: str | None = None,
             progress: Progress | None = None) -> BagData:
    """
    Read the JointState and Float64 topics of a bag.

    Parameters
    ----------
    path : str or PathLike
        Bag folder, storage file, or folder of split storage files.
    state_topic : str or None
        JointState topic; default: the only one in the bag.
    progress : callable or None
        Called now and then with the number of messages read so far.

    Returns
    -------
    BagData
        The decoded content.

    """
    bag = Path(path)
    collected, sources = _collect(bag, lambda msgtype: msgtype in (JOINT_STATE, FLOAT64),
                                  progress)
    topics = tuple(TopicInfo(name, msgtype, count)
                   for name, (msgtype, count) in sorted(collected.topics.items()))
    info = BagInfo(bag, tuple(sources), topics)
    if collected.kept == 0 and collected.declared == 0:
        raise EmptyBagError(f'{bag}: the bag holds no messages')
    state_topics = [name for name, (msgtype, _) in collected.topics.items()
                    if msgtype == JOINT_STATE]
    if state_topic is None:
        if not state_topics:
            raise TopicNotFoundError(f'{bag}: no {JOINT_STATE} topic (topics: {info.describe()})')
        if len(state_topics) > 1:
            preferred = [t for t in state_topics if t.rstrip('/').endswith('joint_states')]
            if len(preferred) != 1:
                listed = ', '.join(state_topics)
                raise TopicNotFoundError(f'{bag}: several JointState topics ({listed}); '
                                         'choose one')
            state_topics = preferred
        state_topic = state_topics[0]
    elif state_topic not in state_topics:
        raise TopicNotFoundError(f'{bag}: no {JOINT_STATE} topic {state_topic} '
                                 f'(topics: {info.describe()})')
    raws = collected.raws.get(state_topic, [])
    if not raws:
        raise DataError(f'{bag}: topic {state_topic} has no messages')
    try:
        decoded = decode_joint_states(raws)
        receive = np.asarray(collected.stamps[state_topic], dtype=np.int64)
        floats = {}
        for name, (msgtype, _) in collected.topics.items():
            if msgtype == FLOAT64:
                floats[name] = Series(name, np.asarray(collected.stamps.get(name, []),
                                                       dtype=np.int64) * 1e-9,
                                      decode_float64(collected.raws.get(name, [])))
    except (TypeError, ValueError, OverflowError) as error:
        if isinstance(error, BagFormatError):
            raise
        # A damaged storage file can hand back NULL or mistyped time stamps and payloads.
        raise BagFormatError(f'{bag}: malformed messages or time stamps ({error})') from None
    # A publisher that never fills header.stamp leaves it at zero; use receive times then.
    stamps = receive if not decoded.stamps.any() else decoded.stamps
    return BagData(bag, state_topic, stamps * 1e-9, decoded.names, decoded.positions,
                   decoded.present, floats, info)


def read_record(path: str | os.PathLike[str], joint: str | None = None,
                command_topic: str | None = None) -> Record:
    """
    Read one joint's record from a bag (see :meth:`BagData.record`).

    Parameters
    ----------
    path : str or PathLike
        The bag.
    joint : str or None
        Joint name; default: the only one.
    command_topic : str or None
        Command topic; default: the only ``valve_command`` topic.

    Returns
    -------
    Record
        The record.

    """
    return read_bag(path).record(joint, command_topic)


def write_bag(path: str | os.PathLike[str], records: Sequence[Record], *,
              storage: str = 'sqlite3',
              setpoints: Mapping[str, FloatArray] | None = None) -> Path:
    """
    Write records as a rosbag2 bag, whole or not at all.

    All records must share their time stamps: each sample becomes one
    ``/joint_states`` message holding every joint (radians) and one
    ``/<joint>/valve_command`` message per joint. A record's ``v_k`` is the
    command in force over the interval ending at ``t_k``, so it is written at
    ``t_{k-1}``, when a controller reading ``y_{k-1}`` would have sent it;
    :meth:`BagData.record` reads it back as ``v_k``.

    Parameters
    ----------
    path : str or PathLike
        Bag folder to create (replaced if it exists).
    records : sequence of Record
        One record per joint.
    storage : str
        ``sqlite3`` or ``mcap``.
    setpoints : mapping of str to FloatArray, optional
        Desired angle (degrees) per joint and sample, written as
        ``/<joint>/setpoint`` in radians.

    Returns
    -------
    Path
        The bag folder.

    """
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import Stores, get_typestore

    if storage not in STORAGES:
        raise ValueError(f"storage must be one of {', '.join(STORAGES)}, got {storage!r}")
    if not records:
        raise DataError('no records to write')
    t = records[0].t
    for record in records[1:]:
        if record.t.shape != t.shape or not np.array_equal(record.t, t):
            raise DataError('records written to one bag must share their time stamps')
    names = [record.joint for record in records]
    if len(set(names)) != len(names) or not all(names):
        raise DataError(f'records need distinct, non-empty joint names, got {names}')
    typestore = get_typestore(Stores.ROS2_JAZZY)
    stamps = np.round(t * 1e9).astype(np.int64)
    if stamps.size < 2:
        raise DataError('a bag needs at least two samples')
    command_stamps = np.r_[2 * stamps[0] - stamps[1], stamps[:-1]]
    if command_stamps[0] < 0:
        raise DataError(f'records must start at least one sample period after t = 0 '
                        f'(first sample at {t[0]} s)')
    template = _joint_state_template(typestore, names)
    positions = np.radians(np.column_stack([record.y for record in records]))
    messages = [('/joint_states', JOINT_STATE, encode_joint_states(template, stamps, positions))]
    for record in records:
        messages.append((f'/{record.joint}/valve_command', FLOAT64, encode_float64(record.v)))
    for joint, values in (setpoints or {}).items():
        values = np.asarray(values, dtype=np.float64)
        if values.shape != t.shape:
            raise DataError(f'setpoints of {joint} do not match the time stamps')
        messages.append((f'/{joint}/setpoint', FLOAT64, encode_float64(np.radians(values))))
    plugin = StoragePlugin.MCAP if storage == 'mcap' else StoragePlugin.SQLITE3
    with atomic_directory(path) as building:
        # Metadata version 8 is what rosbag2 on Jazzy writes and reads.
        with Writer(building, version=8, storage_plugin=plugin) as writer:
            connections = [
                (writer.add_connection(topic, msgtype, typestore=typestore), raws,
                 command_stamps.tolist() if topic.endswith('/valve_command') else stamps.tolist())
                for topic, msgtype, raws in messages]
            for k in range(stamps.size):
                for connection, raws, times in connections:
                    writer.write(connection, times[k], raws[k])
    return Path(path)


def _joint_state_template(typestore, names: Sequence[str]) -> bytes:
    types = typestore.types
    message = types[JOINT_STATE](
        header=types['std_msgs/msg/Header'](
            stamp=types['builtin_interfaces/msg/Time'](sec=0, nanosec=0), frame_id=''),
        name=list(names), position=np.zeros(len(names)),
        velocity=np.zeros(0), effort=np.zeros(0))
    return bytes(typestore.serialize_cdr(message, JOINT_STATE))

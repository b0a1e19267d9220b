"""Records to bags, whole or not at all: rosbags' Writer leaves a partial folder when it fails."""

from __future__ import annotations

from dataclasses import dataclass
import os
from pathlib import Path
from typing import Mapping, Sequence, TYPE_CHECKING

from hydro_sdp.bags.cdr import encode_float64, encode_joint_states
from hydro_sdp.bags.storage import FLOAT64, JOINT_STATE, STORAGES
from hydro_sdp.core.arrays import FloatArray, IntArray
from hydro_sdp.core.errors import DataError
from hydro_sdp.core.model.records import Record
from hydro_sdp.core.model.timing import command_stamps_for
from hydro_sdp.io.atomic import atomic_directory
import numpy as np

if TYPE_CHECKING:
    from rosbags.typesys.store import Typestore


@dataclass(frozen=True, eq=False)
class Stamped:
    """
    Values of one ``std_msgs/msg/Float64`` topic with their own stamps.

    Parameters
    ----------
    stamps : IntArray
        Receive time of each message, integer nanoseconds (any origin, 1970 included).
    values : FloatArray
        The ``data`` fields.

    """

    stamps: IntArray
    values: FloatArray


def _check_storage(storage: str) -> None:
    if storage not in STORAGES:
        raise ValueError(f"storage must be one of {', '.join(STORAGES)}, got {storage!r}")


def write_topics(path: str | os.PathLike[str], stamps: IntArray, names: Sequence[str],
                 positions: FloatArray, floats: Mapping[str, Stamped], *,
                 storage: str = 'sqlite3') -> Path:
    """
    Write ``/joint_states`` and Float64 topics, each at its own stamps, whole or not at all.

    Parameters
    ----------
    path : str or PathLike
        Bag folder to create (replaced if it exists).
    stamps : IntArray
        Stamp of each JointState message, integer nanoseconds (> 0).
    names : sequence of str
        Joint names.
    positions : FloatArray
        ``(messages, joints)`` positions, radians.
    floats : mapping of str to Stamped
        Float64 topics (``/a/b``) and their messages.
    storage : str
        ``sqlite3`` or ``mcap``.

    Returns
    -------
    Path
        The bag folder.

    """
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import get_typestore, Stores

    _check_storage(storage)
    stamps = np.asarray(stamps, dtype=np.int64)
    every = [stamps] + [np.asarray(series.stamps, dtype=np.int64) for series in floats.values()]
    if any(np.any(times < 0) for times in every):
        raise DataError("bag stamps must not be negative (ns since the clock's zero)")
    typestore = get_typestore(Stores.ROS2_JAZZY)
    template = _joint_state_template(typestore, names)
    messages = [('/joint_states', JOINT_STATE, stamps,
                 encode_joint_states(template, stamps, np.asarray(positions)))]
    for topic, series in floats.items():
        values = np.asarray(series.values, dtype=np.float64)
        if values.shape != np.shape(series.stamps):
            raise DataError(f'{topic}: {values.size} values for {np.size(series.stamps)} stamps')
        messages.append((topic, FLOAT64, np.asarray(series.stamps, dtype=np.int64),
                         encode_float64(values)))
    # Every message in time order, as a recorder receives them (stable: topics in the
    # order given at equal stamps).
    topic_of = np.concatenate([np.full(times.size, i) for i, (_, _, times, _) in
                               enumerate(messages)])
    index_of = np.concatenate([np.arange(times.size) for _, _, times, _ in messages])
    order = np.argsort(np.concatenate([times for _, _, times, _ in messages]), kind='stable')
    plugin = StoragePlugin.MCAP if storage == 'mcap' else StoragePlugin.SQLITE3
    with atomic_directory(path) as building:
        # Metadata version 8 is what rosbag2 on Jazzy writes and reads.
        with Writer(building, version=8, storage_plugin=plugin) as writer:
            connections = [writer.add_connection(topic, msgtype, typestore=typestore)
                           for topic, msgtype, _, _ in messages]
            for which, k in zip(topic_of[order].tolist(), index_of[order].tolist()):
                _, _, times, raws = messages[which]
                writer.write(connections[which], int(times[k]), raws[k])
    return Path(path)


def write_bag(path: str | os.PathLike[str], records: Sequence[Record], *,
              storage: str = 'sqlite3',
              setpoints: Mapping[str, FloatArray] | None = None,
              command_topics: Mapping[str, str] | None = None,
              signals: Mapping[str, FloatArray] | None = None, start: int = 0,
              without_command: Sequence[str] = ()) -> Path:
    """
    Write records as a rosbag2 bag, whole or not at all.

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
        ``/<joint>/setpoint`` in radians at the sample stamps.
    command_topics : mapping of str to str, optional
        Command topic per joint, e.g. ``{'arm': '/arm/pwm'}``; default ``/<joint>/valve_command``.
    signals : mapping of str to FloatArray, optional
        More Float64 topics (``/arm/head_pressure``), one value per sample, stamped as the commands
        are, so that the value in force at ``t_k`` (a load read with ``load_topic``) reads back at
        sample ``k``.
    start : int
        Nanoseconds added to every stamp (``1_760_000_000 * 10**9`` stamps the bag
        in 2025, as a recorder on a wall clock does).
    without_command : sequence of str
        Joints whose command topic is not written (measured, not commanded).

    Returns
    -------
    Path
        The bag folder.

    """
    _check_storage(storage)
    if not records:
        raise DataError('no records to write')
    t = records[0].t
    for record in records[1:]:
        if record.t.shape != t.shape or not np.array_equal(record.t, t):
            raise DataError('records written to one bag must share their time stamps')
    names = [record.joint for record in records]
    if len(set(names)) != len(names) or not all(names):
        raise DataError(f'records need distinct, non-empty joint names, got {names}')
    stamps = np.round(t * 1e9).astype(np.int64)
    if stamps.size < 2:
        raise DataError('a bag needs at least two samples')
    command_stamps = command_stamps_for(stamps)
    if command_stamps[0] < 0:
        raise DataError(f'records must start at least one sample period after t = 0 '
                        f'(first sample at {t[0]} s)')
    topics = {record.joint: f'/{record.joint}/valve_command' for record in records}
    for joint, topic in (command_topics or {}).items():
        if joint not in topics:
            raise DataError(f'command topic given for {joint!r}, which has no record')
        topics[joint] = topic
    floats = {topics[record.joint]: Stamped(command_stamps + start, record.v)
              for record in records if record.joint not in without_command}
    for joint, values in (setpoints or {}).items():
        values = np.asarray(values, dtype=np.float64)
        if values.shape != t.shape:
            raise DataError(f'setpoints of {joint} do not match the time stamps')
        floats[f'/{joint}/setpoint'] = Stamped(stamps + start, np.radians(values))
    for topic, values in (signals or {}).items():
        values = np.asarray(values, dtype=np.float64)
        if values.shape != t.shape:
            raise DataError(f'signal {topic} does not match the time stamps')
        if topic in floats:
            raise DataError(f'signal {topic} is also a command or set-point topic')
        floats[topic] = Stamped(command_stamps + start, values)
    positions = np.radians(np.column_stack([record.y for record in records]))
    return write_topics(path, stamps + start, names, positions, floats, storage=storage)


def _joint_state_template(typestore: Typestore, names: Sequence[str]) -> bytes:
    types = typestore.types
    message = types[JOINT_STATE](
        header=types['std_msgs/msg/Header'](
            stamp=types['builtin_interfaces/msg/Time'](sec=0, nanosec=0), frame_id=''),
        name=list(names), position=np.zeros(len(names)),
        velocity=np.zeros(0), effort=np.zeros(0))
    return bytes(typestore.serialize_cdr(message, JOINT_STATE))

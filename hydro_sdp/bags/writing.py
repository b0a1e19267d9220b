"""
Writing records as a rosbag2 bag (sqlite3 or mcap), whole or not at all.

Commands are stamped by :func:`hydro_sdp.core.model.timing.command_stamps_for`, so
that the bag reader pairs each one with the sample it belongs to again.

"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any, Mapping, Sequence

from hydro_sdp.bags.cdr import encode_float64, encode_joint_states
from hydro_sdp.bags.storage import FLOAT64, JOINT_STATE, STORAGES
from hydro_sdp.core.arrays import FloatArray
from hydro_sdp.core.errors import DataError
from hydro_sdp.core.model.records import Record
from hydro_sdp.core.model.timing import command_stamps_for
from hydro_sdp.io.atomic import atomic_directory
import numpy as np


def write_bag(path: str | os.PathLike[str], records: Sequence[Record], *,
              storage: str = 'sqlite3',
              setpoints: Mapping[str, FloatArray] | None = None,
              command_topics: Mapping[str, str] | None = None) -> Path:
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
    command_topics : mapping of str to str, optional
        Command topic per joint, e.g. ``{'arm': '/arm/pwm'}``; default
        ``/<joint>/valve_command``.

    Returns
    -------
    Path
        The bag folder.

    """
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import get_typestore, Stores

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
    command_stamps = command_stamps_for(stamps)
    if command_stamps[0] < 0:
        raise DataError(f'records must start at least one sample period after t = 0 '
                        f'(first sample at {t[0]} s)')
    template = _joint_state_template(typestore, names)
    positions = np.radians(np.column_stack([record.y for record in records]))
    messages = [('/joint_states', JOINT_STATE, encode_joint_states(template, stamps, positions))]
    topics = {record.joint: f'/{record.joint}/valve_command' for record in records}
    for joint, topic in (command_topics or {}).items():
        if joint not in topics:
            raise DataError(f'command topic given for {joint!r}, which has no record')
        topics[joint] = topic
    for record in records:
        messages.append((topics[record.joint], FLOAT64, encode_float64(record.v)))
    for joint, values in (setpoints or {}).items():
        values = np.asarray(values, dtype=np.float64)
        if values.shape != t.shape:
            raise DataError(f'setpoints of {joint} do not match the time stamps')
        messages.append((f'/{joint}/setpoint', FLOAT64, encode_float64(np.radians(values))))
    commands = set(topics.values())
    plugin = StoragePlugin.MCAP if storage == 'mcap' else StoragePlugin.SQLITE3
    with atomic_directory(path) as building:
        # Metadata version 8 is what rosbag2 on Jazzy writes and reads.
        with Writer(building, version=8, storage_plugin=plugin) as writer:
            connections = [
                (writer.add_connection(topic, msgtype, typestore=typestore), raws,
                 command_stamps.tolist() if topic in commands else stamps.tolist())
                for topic, msgtype, raws in messages]
            for k in range(stamps.size):
                for connection, raws, times in connections:
                    writer.write(connection, times[k], raws[k])
    return Path(path)


def _joint_state_template(typestore: Any, names: Sequence[str]) -> bytes:
    types = typestore.types
    message = types[JOINT_STATE](
        header=types['std_msgs/msg/Header'](
            stamp=types['builtin_interfaces/msg/Time'](sec=0, nanosec=0), frame_id=''),
        name=list(names), position=np.zeros(len(names)),
        velocity=np.zeros(0), effort=np.zeros(0))
    return bytes(typestore.serialize_cdr(message, JOINT_STATE))

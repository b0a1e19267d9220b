"""
Conversions between ROS messages and core values (REP 103 at the boundary).

JointState positions are radians on the wire and degrees in the core. The
functions read attributes only, so they serve rclpy messages and rosbags'
deserialised messages alike.

"""

from __future__ import annotations

import math
from math import degrees, isfinite
from typing import Any, Sequence

from hydro_sdp.core.errors import DataError


def stamp_to_ns(stamp: Any) -> int:
    """Return a ``builtin_interfaces/Time`` as integer nanoseconds."""
    return int(stamp.sec) * 1_000_000_000 + int(stamp.nanosec)


def joint_angle(message: Any, joint: str) -> tuple[int, float]:
    """
    Return the stamp (ns) and the angle (degrees) of ``joint`` in a JointState.

    Parameters
    ----------
    message : sensor_msgs/JointState
        The message.
    joint : str
        Joint name.

    Returns
    -------
    tuple[int, float]
        ``(stamp_ns, angle_deg)``.

    Raises
    ------
    DataError
        If the names and positions differ in length, the joint is missing, or its
        position is not finite.

    """
    # The controller calls this for every sample: attributes are read once, nothing copied.
    names = message.name
    positions = message.position
    if len(names) != len(positions):
        raise DataError(f'JointState has {len(names)} names but {len(positions)} positions')
    try:
        index = names.index(joint)
    except ValueError:
        raise DataError(f'joint {joint!r} is not in JointState (names: {list(names)})') from None
    value = float(positions[index])
    if not isfinite(value):
        raise DataError(f'position of joint {joint!r} is not finite ({value})')
    stamp = message.header.stamp
    return int(stamp.sec) * 1_000_000_000 + int(stamp.nanosec), degrees(value)


def fill_joint_state(message: Any, stamp_ns: int, names: Sequence[str],
                     angles_deg: Sequence[float],
                     speeds_deg: Sequence[float] | None = None) -> Any:
    """
    Fill a JointState message (stamp, names, positions and velocities in radians).

    Parameters
    ----------
    message : sensor_msgs/JointState
        Message to fill.
    stamp_ns : int
        Stamp, nanoseconds.
    names : sequence of str
        Joint names.
    angles_deg : sequence of float
        Angles, degrees.
    speeds_deg : sequence of float or None
        Angular velocities, deg/s.

    Returns
    -------
    sensor_msgs/JointState
        The message.

    """
    message.header.stamp.sec = int(stamp_ns // 1_000_000_000)
    message.header.stamp.nanosec = int(stamp_ns % 1_000_000_000)
    message.name = list(names)
    message.position = [math.radians(a) for a in angles_deg]
    if speeds_deg is not None:
        message.velocity = [math.radians(s) for s in speeds_deg]
    return message

"""Conversions between ROS messages and core values (REP 103 at the boundary)."""

from __future__ import annotations

import math
from math import degrees, isfinite
from typing import Protocol, Sequence, TypeVar

from hydro_sdp.core.control.trajectory import JointTrajectory
from hydro_sdp.core.errors import DataError
import numpy as np


class TimeField(Protocol):
    """A ``builtin_interfaces/Time`` or ``Duration``."""

    sec: int
    nanosec: int


class HeaderField(Protocol):
    """A ``std_msgs/Header``."""

    stamp: TimeField


class JointStateMessage(Protocol):
    """A ``sensor_msgs/JointState`` (rclpy's, or rosbags' deserialised one)."""

    header: HeaderField
    name: Sequence[str]
    position: Sequence[float]
    velocity: Sequence[float]


class TrajectoryPointMessage(Protocol):
    """A ``trajectory_msgs/JointTrajectoryPoint``."""

    positions: Sequence[float]
    velocities: Sequence[float]
    time_from_start: TimeField


class TrajectoryMessage(Protocol):
    """A ``trajectory_msgs/JointTrajectory``."""

    header: HeaderField
    joint_names: Sequence[str]
    points: Sequence[TrajectoryPointMessage]


class ArrayMessage(Protocol):
    """A ``std_msgs/Float64MultiArray`` (its layout set elsewhere)."""

    data: Sequence[float]


JointStateT = TypeVar('JointStateT', bound=JointStateMessage)
TrajectoryT = TypeVar('TrajectoryT', bound=TrajectoryMessage)
ArrayT = TypeVar('ArrayT', bound=ArrayMessage)


def stamp_to_ns(stamp: TimeField) -> int:
    """Return a ``builtin_interfaces/Time`` as integer nanoseconds."""
    return int(stamp.sec) * 1_000_000_000 + int(stamp.nanosec)


def fill_stamp(stamp: TimeField, stamp_ns: int) -> None:
    """Set a ``builtin_interfaces/Time`` to ``stamp_ns`` integer nanoseconds."""
    stamp.sec, stamp.nanosec = divmod(int(stamp_ns), 1_000_000_000)


def joint_angle(message: JointStateMessage, joint: str) -> tuple[int, float]:
    """Return the stamp (ns) and the angle (degrees) of ``joint`` in a JointState."""
    return stamp_to_ns(message.header.stamp), position_of(message.name, message.position, joint)


def position_of(names: Sequence[str], positions: Sequence[float], joint: str) -> float:
    """
    Return the angle (degrees) of ``joint`` from a JointState's ``name`` and ``position``.

    ``names``: the message's joint names.
    ``positions``: its positions, rad.
    Returns: the angle, degrees.
    Raises DataError if the names and positions differ in length, the joint is missing, or its
    position is not finite.
    """
    # The controller calls this for every sample and joint: nothing is copied.
    if len(names) != len(positions):
        raise DataError(f'JointState has {len(names)} names but {len(positions)} positions')
    try:
        index = names.index(joint)
    except ValueError:
        raise DataError(f'joint {joint!r} is not in JointState (names: {list(names)})') from None
    value = float(positions[index])
    if not isfinite(value):
        raise DataError(f'position of joint {joint!r} is not finite ({value})')
    return degrees(value)


def fill_joint_state(message: JointStateT, stamp_ns: int, names: Sequence[str],
                     angles_deg: Sequence[float],
                     speeds_deg: Sequence[float] | None = None) -> JointStateT:
    """Fill a JointState message (stamp, names, positions and velocities in radians)."""
    fill_stamp(message.header.stamp, stamp_ns)
    message.name = list(names)
    message.position = [math.radians(a) for a in angles_deg]
    if speeds_deg is not None:
        message.velocity = [math.radians(s) for s in speeds_deg]
    return message


def trajectory_from_message(message: TrajectoryMessage) -> tuple[JointTrajectory, float]:
    """
    Return a ``trajectory_msgs/JointTrajectory`` in core units, and its stamp.

    ``message``: positions in rad, velocities in rad/s, ``time_from_start`` per point.
    Returns: the trajectory in degrees (velocities in deg/s, kept only when every point gives one
    per joint) and the header stamp, s (0: start now).
    Raises DataError if a point has the wrong number of positions, or the trajectory is not valid.
    """
    names = tuple(message.joint_names)
    points = list(message.points)
    if not points:
        raise DataError('trajectory refused: it has no points')
    wrong = [index for index, point in enumerate(points) if len(point.positions) != len(names)]
    if wrong:
        raise DataError(f'trajectory refused: points {wrong} do not have one position per '
                        f'joint ({len(names)})')
    times = [int(p.time_from_start.sec) + int(p.time_from_start.nanosec) * 1e-9 for p in points]
    positions = np.degrees(np.array([list(p.positions) for p in points], dtype=np.float64))
    velocities = None
    if all(len(point.velocities) == len(names) for point in points):
        velocities = np.degrees(np.array([list(p.velocities) for p in points],
                                         dtype=np.float64))
    try:
        trajectory = JointTrajectory(names, np.array(times), positions, velocities)
    except DataError as error:
        raise DataError(f'trajectory refused: {error}') from None
    return trajectory, stamp_to_ns(message.header.stamp) * 1e-9


def fill_trajectory(message: TrajectoryT, names: Sequence[str], times: Sequence[float],
                    positions_deg: Sequence[Sequence[float]], stamp_ns: int = 0) -> TrajectoryT:
    """
    Fill a ``trajectory_msgs/JointTrajectory`` (positions in rad).

    ``message``: message to fill (its points are built with its own point type).
    ``times``: time from start of each point, s.
    ``positions_deg``: one row of angles (deg) per point, one value per joint.
    ``stamp_ns``: header stamp, ns (0: start on arrival).
    """
    from trajectory_msgs.msg import JointTrajectoryPoint
    fill_stamp(message.header.stamp, stamp_ns)
    message.joint_names = list(names)
    points = []
    for t, row in zip(times, positions_deg):
        point = JointTrajectoryPoint(positions=[math.radians(a) for a in row])
        whole = math.floor(t)
        point.time_from_start.sec = int(whole)
        point.time_from_start.nanosec = int(round((t - whole) * 1e9))
        points.append(point)
    message.points = points
    return message


#: Layout of ``<joint>/controller_state`` (``std_msgs/Float64MultiArray``): one dimension
#: of size 5 whose label lists, in data order, the set-point, angle and error (set-point less
#: angle) in rad, the increment ``u`` in rad per control sample, the valve command ``v`` in
#: input units.
CONTROLLER_STATE_LABELS = ('setpoint_rad', 'angle_rad', 'error_rad', 'u_rad_per_sample',
                           'v_command')


def fill_controller_state(message: ArrayT, setpoint_deg: float, angle_deg: float,
                          u_deg: float, v: float) -> ArrayT:
    """
    Fill a ``Float64MultiArray`` with one control step (layout: :data:`CONTROLLER_STATE_LABELS`).

    ``message``: message whose ``layout`` is already set (:data:`CONTROLLER_STATE_LABELS`).
    ``setpoint_deg``, ``angle_deg``: set-point and measured angle, degrees.
    ``u_deg``: increment applied, degrees per control sample.
    ``v``: valve command, input units.
    """
    setpoint, angle = math.radians(setpoint_deg), math.radians(angle_deg)
    message.data = [setpoint, angle, setpoint - angle, math.radians(u_deg), float(v)]
    return message

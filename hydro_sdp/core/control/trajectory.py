"""Joint trajectories as a ``JointTrajectoryController`` user expects them (methods 4.9-4.10)."""

from __future__ import annotations

from bisect import bisect_right
from dataclasses import dataclass
import math
from typing import Mapping, Sequence

from hydro_sdp.core.arrays import FloatArray
from hydro_sdp.core.control.safety import SETPOINT_MARGIN, setpoint_range
from hydro_sdp.core.errors import DataError
from hydro_sdp.core.model.timing import SamplePeriod
import numpy as np


@dataclass(frozen=True, eq=False)
class JointTrajectory:
    """
    Points for several joints, as ``trajectory_msgs/JointTrajectory`` in degrees.

    Raises DataError naming what is wrong (names, lengths, times, values).

    Attributes
    ----------
    times : FloatArray
        Time from start of each point, s: finite, >= 0, strictly increasing.
    positions : FloatArray
        Positions, degrees, one row per point and one column per joint.
    velocities : FloatArray or None
        Velocities, deg/s, same shape as ``positions`` (``None``: linear interpolation).

    """

    joint_names: tuple[str, ...]
    times: FloatArray
    positions: FloatArray
    velocities: FloatArray | None = None

    def __post_init__(self) -> None:
        names = tuple(self.joint_names)
        if not names or any(not isinstance(name, str) or not name for name in names):
            raise DataError(f'a trajectory needs joint names, got {list(names)}')
        repeated = sorted({name for name in names if names.count(name) > 1})
        if repeated:
            raise DataError(f"joint names must be unique; repeated: {', '.join(repeated)}")
        times = np.asarray(self.times, dtype=np.float64).reshape(-1)
        positions = np.asarray(self.positions, dtype=np.float64)
        if times.size == 0:
            raise DataError('a trajectory needs at least one point')
        if positions.shape != (times.size, len(names)):
            raise DataError(f'positions must have one row per point and one value per joint '
                            f'({times.size} x {len(names)}), got shape {positions.shape}')
        if not np.all(np.isfinite(times)) or times[0] < 0.0:
            raise DataError('times from start must be finite and >= 0 s')
        if np.any(np.diff(times) <= 0.0):
            raise DataError('times from start must be strictly increasing')
        if not np.all(np.isfinite(positions)):
            raise DataError('positions must be finite')
        velocities = self.velocities
        if velocities is not None:
            velocities = np.asarray(velocities, dtype=np.float64)
            if velocities.shape != positions.shape:
                raise DataError(f'velocities must have the shape of the positions '
                                f'{positions.shape}, got {velocities.shape}')
            if not np.all(np.isfinite(velocities)):
                raise DataError('velocities must be finite')
            velocities.setflags(write=False)
        times.setflags(write=False)
        positions.setflags(write=False)
        object.__setattr__(self, 'joint_names', names)
        object.__setattr__(self, 'times', times)
        object.__setattr__(self, 'positions', positions)
        object.__setattr__(self, 'velocities', velocities)

    @property
    def duration(self) -> float:
        """Time from start of the last point, s."""
        return float(self.times[-1])


def check_trajectory(trajectory: JointTrajectory,
                     angle_limits: Mapping[str, tuple[float, float] | None],
                     margin: float = SETPOINT_MARGIN) -> None:
    """
    Refuse a trajectory for joints not controlled or beyond the end stops.

    ``angle_limits``: end stops of each controlled joint, degrees (``None``: no stops).
    ``margin``: distance kept from the stops, degrees (as :func:`~.safety.setpoint_range`).
    Raises DataError with one message naming every joint not controlled and every joint whose
    positions leave the allowed range (its extreme position and the range).
    """
    unknown = [name for name in trajectory.joint_names if name not in angle_limits]
    beyond = []
    for column, name in enumerate(trajectory.joint_names):
        if name in unknown:
            continue
        allowed = setpoint_range(angle_limits[name], margin)
        if allowed is None:
            continue
        values = trajectory.positions[:, column]
        low, high = float(values.min()), float(values.max())
        if low < allowed[0] or high > allowed[1]:
            worst = low if low < allowed[0] else high
            beyond.append(f'{name} reaches {worst:g} deg (allowed [{allowed[0]:g}, '
                          f'{allowed[1]:g}])')
    problems = []
    if unknown:
        problems.append(f"joints not controlled: {', '.join(unknown)}")
    if beyond:
        problems.append(f"beyond the end stops less {margin:g} deg: {'; '.join(beyond)}")
    if problems:
        raise DataError(f"trajectory refused: {'; '.join(problems)}")


def check_trajectory_speeds(rates: Mapping[str, tuple[float, float]],
                            top_speeds: Mapping[str, tuple[float, float] | None]) -> None:
    """
    Refuse a trajectory whose set-point would move faster than a joint's top speed.

    ``rates``: lowest and highest set-point rate of each joint it names, deg/s
    (:meth:`TrajectorySampler.planned_rates`).
    ``top_speeds``: each joint's identified top speeds down (<= 0) and up, deg/s (None: unknown).
    Raises DataError with one message naming every joint too fast, its rate and its top speed.
    """
    fast = []
    for name, (low, high) in rates.items():
        top = top_speeds.get(name)
        if top is None:
            continue
        if low < top[0]:
            fast.append(f'{name} at {low:.4g} deg/s (top speed down {top[0]:.4g})')
        if high > top[1]:
            fast.append(f'{name} at {high:.4g} deg/s (top speed up {top[1]:.4g})')
    if fast:
        raise DataError(f"trajectory refused: faster than the joint can move: {'; '.join(fast)}")


def start_time(stamp: float, now: float) -> float:
    """Return when a trajectory starts: its stamp, or ``now`` when the stamp is zero."""
    return float(now) if stamp == 0.0 else float(stamp)


@dataclass(frozen=True, eq=False)
class _Piece:
    """One joint's part of a trajectory, in absolute time, anchor point included."""

    times: tuple[float, ...]
    positions: tuple[float, ...]
    velocities: tuple[float, ...] | None

    @property
    def start(self) -> float:
        return self.times[0]

    def rate_range(self) -> tuple[float, float]:
        # The lowest and highest set-point rate over the piece, deg/s: per segment the
        # chord, or the extremes of the cubic's derivative (a quadratic in s on [0, 1]).
        times, positions = self.times, self.positions
        low = high = 0.0
        for i in range(len(times) - 1):
            span = times[i + 1] - times[i]
            change = positions[i + 1] - positions[i]
            if self.velocities is None:
                rates = [change / span]
            else:
                m0, m1 = self.velocities[i] * span, self.velocities[i + 1] * span
                a, b = -6.0 * change + 3.0 * (m0 + m1), 6.0 * change - 4.0 * m0 - 2.0 * m1
                slopes = [m0, m1]
                if a != 0.0 and 0.0 < -b / (2.0 * a) < 1.0:
                    s = -b / (2.0 * a)
                    slopes.append(a * s * s + b * s + m0)
                rates = [slope / span for slope in slopes]
            low, high = min(low, *rates), max(high, *rates)
        return low, high

    def sample(self, t: float) -> tuple[float, float]:
        times, positions = self.times, self.positions
        if t >= times[-1]:
            return positions[-1], 0.0
        i = max(bisect_right(times, t) - 1, 0)
        span = times[i + 1] - times[i]
        s = (t - times[i]) / span
        p0, p1 = positions[i], positions[i + 1]
        if self.velocities is None:
            return p0 + s * (p1 - p0), (p1 - p0) / span
        # Cubic Hermite on [0, 1] with the end tangents scaled by the span.
        m0, m1 = self.velocities[i] * span, self.velocities[i + 1] * span
        s2, s3 = s * s, s * s * s
        position = ((2 * s3 - 3 * s2 + 1) * p0 + (s3 - 2 * s2 + s) * m0
                    + (-2 * s3 + 3 * s2) * p1 + (s3 - s2) * m1)
        slope = ((6 * s2 - 6 * s) * p0 + (3 * s2 - 4 * s + 1) * m0
                 + (-6 * s2 + 6 * s) * p1 + (3 * s2 - 2 * s) * m1)
        return position, slope / span


class TrajectorySampler:
    """
    The set-point and set-point rate of each joint at any time.

    ``setpoints``: controlled joints and the set-point each holds until a trajectory comes,
    degrees.
    """

    def __init__(self, setpoints: Mapping[str, float]) -> None:
        self._hold = {name: float(value) for name, value in setpoints.items()}
        for name, value in self._hold.items():
            if not math.isfinite(value):
                raise DataError(f'the set-point of joint {name} must be finite, got {value}')
        self._pieces: dict[str, list[_Piece]] = {name: [] for name in self._hold}

    @property
    def joints(self) -> tuple[str, ...]:
        """Return the controlled joints."""
        return tuple(self._hold)

    def sample(self, joint: str, t: float) -> tuple[float, float]:
        """Return the set-point (deg) and its rate (deg/s) of ``joint`` at time ``t`` (s)."""
        pieces = self._pieces[joint]
        for piece in reversed(pieces):
            if piece.start <= t:
                return piece.sample(t)
        return self._hold[joint], 0.0

    def sample_all(self, t: float) -> dict[str, tuple[float, float]]:
        """Return ``(setpoint, rate)`` of every joint at time ``t`` (s): deg and deg/s."""
        return {joint: self.sample(joint, t) for joint in self._hold}

    def setpoint(self, joint: str, t: float) -> float:
        """Return the set-point of ``joint`` at time ``t`` (s), degrees."""
        return self.sample(joint, t)[0]

    def feedforward(self, joint: str, t: float, control_period: SamplePeriod, lead: int) -> float:
        """Set-point increment over one control period ending ``lead`` periods after ``t``."""
        ahead = t + lead * control_period
        return self.setpoint(joint, ahead) - self.setpoint(joint, ahead - control_period)

    def end_time(self, joint: str) -> float:
        """Time after which ``joint`` holds its last set-point, s (``-inf`` if never moved)."""
        pieces = self._pieces[joint]
        return pieces[-1].times[-1] if pieces else -math.inf

    def hold(self, joint: str, position: float, start: float) -> None:
        """
        Hold ``joint`` at ``position`` (deg) from ``start`` (s) on, replacing what follows.

        ``start``: time from which it holds, s.
        """
        point = np.full((1, 1), float(position))
        self.replace(JointTrajectory((joint,), np.zeros(1), point), start)

    def replace(self, trajectory: JointTrajectory, start: float) -> None:
        """Follow ``trajectory`` from ``start`` on, replacing the rest of what was planned."""
        for name, piece in self._planned(trajectory, start).items():
            kept = [old for old in self._pieces[name] if old.start < start]
            kept.append(piece)
            self._pieces[name] = kept

    def planned_rates(self, trajectory: JointTrajectory,
                      start: float) -> dict[str, tuple[float, float]]:
        """
        Return the lowest and highest set-point rate (deg/s) ``trajectory`` would give each joint.

        ``start``: its start time, s.
        """
        return {name: piece.rate_range()
                for name, piece in self._planned(trajectory, start).items()}

    def _planned(self, trajectory: JointTrajectory, start: float) -> dict[str, _Piece]:
        if not math.isfinite(start):
            raise DataError(f'the start time must be finite, got {start}')
        unknown = [name for name in trajectory.joint_names if name not in self._hold]
        if unknown:
            raise DataError(f"trajectory refused: joints not controlled: {', '.join(unknown)}")
        times = [start + float(t) for t in trajectory.times]
        planned = {}
        for column, name in enumerate(trajectory.joint_names):
            anchor, rate = self.sample(name, start)
            positions = [float(p) for p in trajectory.positions[:, column]]
            velocities = (None if trajectory.velocities is None
                          else [float(v) for v in trajectory.velocities[:, column]])
            piece_times = list(times)
            if times[0] > start:
                piece_times.insert(0, start)
                positions.insert(0, anchor)
                if velocities is not None:
                    velocities.insert(0, rate)
            planned[name] = _Piece(tuple(piece_times), tuple(positions),
                                   None if velocities is None else tuple(velocities))
        return planned

    def prune(self, now: float) -> None:
        """Forget the pieces no sample at or after ``now`` (s) can reach."""
        for name, pieces in self._pieces.items():
            in_force = [i for i, piece in enumerate(pieces) if piece.start <= now]
            if in_force:
                self._pieces[name] = pieces[in_force[-1]:]

    def setpoints(self, joint: str, times: Sequence[float] | FloatArray) -> FloatArray:
        """Return the set-points of ``joint`` at many times."""
        return np.array([self.setpoint(joint, float(t)) for t in times], dtype=np.float64)

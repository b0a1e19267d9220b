"""Planar two-link kinematics of a boom and a dipper, and straight tip lines (methods 4.10)."""

from __future__ import annotations

from dataclasses import dataclass
import math

from hydro_sdp.core.control.trajectory import JointTrajectory
from hydro_sdp.core.errors import DataError, ModelFileError
from hydro_sdp.core.validation import read_document, require_float, require_mapping
import numpy as np

KINEMATICS_FORMAT = 'hydro_sdp/kinematics/v1'

#: Elbow choices of the inverse: 'up' puts the boom-dipper joint above the line
#: from the pivot to the tip (the dipper folded down, as on an excavator).
ELBOWS = ('up', 'down')


def _wrap(angle: float) -> float:
    """Return ``angle`` (deg) in (-180, 180]."""
    wrapped = math.fmod(angle + 180.0, 360.0)
    wrapped = wrapped + 360.0 if wrapped <= 0.0 else wrapped
    return wrapped - 180.0


@dataclass(frozen=True)
class TwoLinkArm:
    """
    Boom and dipper as a planar two-link arm.

    Attributes
    ----------
    lengths : tuple[float, float]
        Link lengths (pivot to pivot, dipper pivot to bucket tip), m.
    offsets : tuple[float, float]
        Angle offsets added to the joint angles, degrees.

    """

    joints: tuple[str, str]
    lengths: tuple[float, float]
    offsets: tuple[float, float] = (0.0, 0.0)

    def __post_init__(self) -> None:
        if len(self.joints) != 2 or self.joints[0] == self.joints[1]:
            raise ModelFileError(f'two different joints are needed, got {list(self.joints)}')
        if any(not (math.isfinite(x) and x > 0.0) for x in self.lengths):
            raise ModelFileError(f'link lengths must be finite and > 0 m, '
                                 f'got {list(self.lengths)}')
        if any(not math.isfinite(x) for x in self.offsets):
            raise ModelFileError(f'offsets must be finite, got {list(self.offsets)}')

    @classmethod
    def from_mapping(cls, data: object) -> TwoLinkArm:
        """
        Validate a mapping read from a kinematics file and build the arm.

        Raises ModelFileError naming the key and the reason.
        """
        data = read_document(data, 'a kinematics file', KINEMATICS_FORMAT,
                             known=('format', 'links'), required=('format', 'links'))
        links = data['links']
        if not isinstance(links, list) or len(links) != 2:
            raise ModelFileError("key 'links': expected a list of two links (boom, dipper)")
        joints, lengths, offsets = [], [], []
        for index, link in enumerate(links):
            where = f'links[{index}]'
            link = require_mapping(link, where, ('joint', 'length', 'offset'),
                                   ('joint', 'length'),
                                   expected='a mapping with joint, length and offset')
            if not isinstance(link['joint'], str) or not link['joint']:
                raise ModelFileError(f"key '{where}.joint': expected a name, "
                                     f"got {link['joint']!r}")
            length = require_float(link['length'], f'{where}.length')
            if length <= 0.0:
                raise ModelFileError(f"key '{where}.length': must be > 0 m, got {length}")
            joints.append(link['joint'])
            lengths.append(length)
            offsets.append(require_float(link.get('offset', 0.0), f'{where}.offset'))
        if joints[0] == joints[1]:
            raise ModelFileError(f"key 'links': the two links name the same joint {joints[0]!r}")
        return cls((joints[0], joints[1]), (lengths[0], lengths[1]), (offsets[0], offsets[1]))

    @property
    def reach(self) -> tuple[float, float]:
        """Smallest and largest distance of the tip from the pivot, m."""
        return abs(self.lengths[0] - self.lengths[1]), self.lengths[0] + self.lengths[1]

    def forward(self, boom: float, dipper: float) -> tuple[float, float]:
        """
        Return the tip ``(x, z)`` (m) for the joint angles (deg).

        ``boom``, ``dipper``: joint angles, degrees.
        Returns: tip position, m.
        """
        phi1 = math.radians(boom + self.offsets[0])
        phi2 = phi1 + math.radians(dipper + self.offsets[1])
        l1, l2 = self.lengths
        return l1 * math.cos(phi1) + l2 * math.cos(phi2), l1 * math.sin(phi1) + l2 * math.sin(phi2)

    def forward_many(self, boom: np.ndarray, dipper: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Vectorised :meth:`forward`: arrays of angles (deg) to arrays of ``x``, ``z`` (m)."""
        phi1 = np.radians(np.asarray(boom, dtype=np.float64) + self.offsets[0])
        phi2 = phi1 + np.radians(np.asarray(dipper, dtype=np.float64) + self.offsets[1])
        l1, l2 = self.lengths
        return l1 * np.cos(phi1) + l2 * np.cos(phi2), l1 * np.sin(phi1) + l2 * np.sin(phi2)

    def inverse(self, x: float, z: float, elbow: str = 'up') -> tuple[float, float]:
        """
        Return the joint angles (deg) that put the tip at ``(x, z)`` (m).

        ``x``, ``z``: tip position, m.
        ``elbow``: ``'up'`` (dipper angle relative to the boom <= 0) or ``'down'``.
        Returns: boom and dipper angles, degrees, each in (-180, 180].
        Raises DataError if the point is out of reach (with the reach) or ``elbow`` is unknown.
        """
        if elbow not in ELBOWS:
            raise DataError(f"elbow must be one of {', '.join(ELBOWS)}, got {elbow!r}")
        if not (math.isfinite(x) and math.isfinite(z)):
            raise DataError(f'the tip position must be finite, got ({x}, {z})')
        l1, l2 = self.lengths
        distance = math.hypot(x, z)
        cosine = (distance * distance - l1 * l1 - l2 * l2) / (2.0 * l1 * l2)
        if not -1.0 - 1e-12 <= cosine <= 1.0 + 1e-12:
            near, far = self.reach
            raise DataError(f'the point ({x:g}, {z:g}) m is out of reach: its distance '
                            f'{distance:.4g} m from the boom pivot is outside [{near:.4g}, '
                            f'{far:.4g}] m')
        relative = math.acos(min(max(cosine, -1.0), 1.0))
        relative = -relative if elbow == 'up' else relative
        phi1 = math.atan2(z, x) - math.atan2(l2 * math.sin(relative),
                                             l1 + l2 * math.cos(relative))
        return (_wrap(math.degrees(phi1) - self.offsets[0]),
                _wrap(math.degrees(relative) - self.offsets[1]))

    def jacobian(self, boom: float, dipper: float) -> np.ndarray:
        """
        Return ``d(x, z) / d(boom, dipper)`` at the joint angles (deg), m per degree.

        A 2 x 2 matrix, rows ``x`` and ``z``.

        """
        phi1 = math.radians(boom + self.offsets[0])
        phi2 = phi1 + math.radians(dipper + self.offsets[1])
        l1, l2 = self.lengths
        per_degree = math.pi / 180.0
        return per_degree * np.array([
            [-l1 * math.sin(phi1) - l2 * math.sin(phi2), -l2 * math.sin(phi2)],
            [l1 * math.cos(phi1) + l2 * math.cos(phi2), l2 * math.cos(phi2)]])


def line_trajectory(arm: TwoLinkArm, start: tuple[float, float], end: tuple[float, float], *,
                    speed: float | None = None, duration: float | None = None,
                    point_period: float = 0.05, elbow: str = 'up') -> JointTrajectory:
    """
    Joint trajectory that moves the tip along a straight line at constant speed.

    ``start``, ``end``: ends of the line ``(x, z)``, m.
    ``speed``: tip speed, m/s (give this or ``duration``).
    ``duration``: time from start to end, s.
    ``point_period``: time between points, s.
    Raises DataError if the line is empty, the timing is missing or invalid, or a point is out of
    reach.
    """
    p0, p1 = np.asarray(start, dtype=np.float64), np.asarray(end, dtype=np.float64)
    length = float(np.hypot(*(p1 - p0)))
    if p0.shape != (2,) or p1.shape != (2,) or not np.all(np.isfinite(np.r_[p0, p1])):
        raise DataError('the line ends must be two finite (x, z) points')
    if length == 0.0:
        raise DataError('the line ends must differ')
    if (speed is None) == (duration is None):
        raise DataError('give the speed or the duration of the line, not both')
    if speed is not None:
        if not (math.isfinite(speed) and speed > 0.0):
            raise DataError(f'the speed must be > 0 m/s, got {speed}')
        duration = length / speed
    assert duration is not None
    if not (math.isfinite(duration) and duration > 0.0):
        raise DataError(f'the duration must be > 0 s, got {duration}')
    if not (math.isfinite(point_period) and point_period > 0.0):
        raise DataError(f'the point period must be > 0 s, got {point_period}')
    count = max(1, int(math.ceil(duration / point_period - 1e-9)))
    times = np.minimum(np.arange(count + 1) * point_period, duration)
    velocity = (p1 - p0) / duration
    positions, velocities = [], []
    for t in times:
        x, z = p0 + (p1 - p0) * (t / duration)
        angles = arm.inverse(float(x), float(z), elbow)
        positions.append(angles)
        velocities.append(np.linalg.solve(arm.jacobian(*angles), velocity))
    return JointTrajectory(arm.joints, times, np.array(positions), np.array(velocities))


def distance_to_segment(x: np.ndarray, z: np.ndarray, start: tuple[float, float],
                        end: tuple[float, float]) -> np.ndarray:
    """Return the distance of points from the segment ``start``-``end``, same unit."""
    p0, p1 = np.asarray(start, dtype=np.float64), np.asarray(end, dtype=np.float64)
    direction = p1 - p0
    points = np.stack([np.asarray(x, dtype=np.float64), np.asarray(z, dtype=np.float64)], -1)
    s = np.clip((points - p0) @ direction / float(direction @ direction), 0.0, 1.0)
    nearest = p0 + s[..., None] * direction
    return np.hypot(*(points - nearest).T)

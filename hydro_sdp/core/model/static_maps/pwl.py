"""The monotone piecewise-linear map (kind ``pwl``), for valves that do not follow eq. (5)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

from hydro_sdp.core.arrays import FloatArray
from hydro_sdp.core.errors import ModelFileError
from hydro_sdp.core.model.static_maps.protocol import MapKind
from hydro_sdp.core.validation import Document, require_float_list
import numpy as np


@dataclass(frozen=True)
class PwlMap:
    """
    Monotone piecewise-linear map (kind ``pwl``), for valves that do not follow eq. (5).

    Parameters
    ----------
    knots : tuple[float, ...]
        Commands, strictly increasing (at least two), input units.
    speeds : tuple[float, ...]
        Velocity at each knot, deg/s, non-decreasing; held flat beyond the end knots.

    """

    kind: ClassVar[MapKind] = 'pwl'
    keys: ClassVar[tuple[str, ...]] = ('knots', 'speeds')

    knots: tuple[float, ...]
    speeds: tuple[float, ...]

    def __post_init__(self) -> None:
        knots = tuple(float(x) for x in self.knots)
        speeds = tuple(float(x) for x in self.speeds)
        if len(knots) < 2 or len(knots) != len(speeds):
            raise ModelFileError("keys 'knots' and 'speeds': need two or more of each, "
                                 'of equal number')
        if not all(np.isfinite(knots + speeds)):
            raise ModelFileError("keys 'knots' and 'speeds': values must be finite")
        if np.any(np.diff(knots) <= 0.0):
            raise ModelFileError("key 'knots': must be strictly increasing")
        if np.any(np.diff(speeds) < 0.0):
            raise ModelFileError("key 'speeds': must not decrease (a monotone valve map)")
        object.__setattr__(self, 'knots', knots)
        object.__setattr__(self, 'speeds', speeds)

    @property
    def dead_zone(self) -> tuple[float, float] | None:
        """Return the commands bounding the zero-speed plateau, or None if there is none."""
        zero = [k for k, speed in zip(self.knots, self.speeds) if speed == 0.0]
        if not zero:
            return None
        return zero[0], zero[-1]

    def rate(self, v: FloatArray) -> FloatArray:
        """Angular velocity (deg/s) for steady commands ``v`` (:meth:`StaticMap.rate`)."""
        return np.interp(np.asarray(v, dtype=np.float64), self.knots, self.speeds)

    def to_mapping(self) -> dict[str, float | list[float]]:
        """Return the model-file keys of this map."""
        return {'knots': list(self.knots), 'speeds': list(self.speeds)}

    @classmethod
    def from_mapping(cls, data: Document) -> PwlMap:
        """Build the map from model-file keys (already checked for presence)."""
        return cls(knots=require_float_list(data['knots'], 'knots'),
                   speeds=require_float_list(data['speeds'], 'speeds'))

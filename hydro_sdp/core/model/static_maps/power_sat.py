"""
The saturating power-law map (kind ``power_sat``, methods 2.7 and 13.4).

``V (1 - exp(-(c u)^n))`` with ``u`` the distance beyond the dead-zone edge; ``n = 1`` is eq. (5).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
import math
from typing import ClassVar

from hydro_sdp.core.arrays import FloatArray
from hydro_sdp.core.model.static_maps.protocol import (
    check_dead_zone, check_positive_pair, check_saturation_velocity, MapKind)
from hydro_sdp.core.validation import Document, require_ordered_pair, require_pair
import numpy as np


def power_sat_rate(v: FloatArray | float, vn: float, cn: float, nn: float, a3: float,
                   vp: float, cp: float, np_: float, a6: float) -> FloatArray:
    """
    Evaluate ``vn (1 - exp(-(cn (a3 - v))^nn))`` below ``a3``, 0 inside, ``vp (..)`` above ``a6``.

    ``v``: commands, input units.
    ``vn``, ``vp``: negative and positive saturation speeds, deg/s.
    ``cn``, ``cp``: scales, 1/input unit.
    ``nn``, ``np_``: exponents (> 0; 1 gives eq. (5)).
    ``a3``, ``a6``: dead-zone edges, input units.
    """
    v = np.asarray(v, dtype=np.float64)
    if v.size == 1:
        one = _one_rate(float(v.flat[0]), vn, cn, nn, a3, vp, cp, np_, a6)
        if one is not None:
            return np.full(v.shape, one)[()]     # a scalar for a 0-d v, as below
    below = np.maximum(a3 - v, 0.0)
    above = np.maximum(v - a6, 0.0)
    return vn * -np.expm1(-(cn * below) ** nn) + vp * -np.expm1(-(cp * above) ** np_)


def _one_rate(v: float, vn: float, cn: float, nn: float, a3: float, vp: float, cp: float,
              np_: float, a6: float) -> float | None:
    """Return :func:`power_sat_rate` of one command, bit for bit; None where it overflows."""
    # A simulation's step asks for one command at a time, where numpy's overhead is most
    # of the cost. numpy takes x ** 2 as x * x and x ** 0.5 as a square root: so does this.
    def power(x: float, n: float) -> float:
        return x * x if n == 2.0 else math.sqrt(x) if n == 0.5 else x ** n
    try:
        return (vn * -math.expm1(-power(cn * max(a3 - v, 0.0), nn))
                + vp * -math.expm1(-power(cp * max(v - a6, 0.0), np_)))
    except (OverflowError, ValueError):
        return None


@dataclass(frozen=True)
class PowerSatMap:
    """
    Saturating power-law map with dead-zone (kind ``power_sat``).

    Parameters
    ----------
    dead_zone : tuple[float, float]
        Edges ``(a3, a6)``, input units.
    saturation_velocity : tuple[float, float]
        Speeds approached for large commands, deg/s; negative first, ``vn < 0 < vp``.
    curvature : tuple[float, float]
        Scales ``(cn, cp)`` of the distance beyond each edge, 1/input unit (> 0).
    exponent : tuple[float, float]
        Powers ``(nn, np)`` (> 0): above 1 the map starts convexly from the edge.

    """

    kind: ClassVar[MapKind] = 'power_sat'
    keys: ClassVar[tuple[str, ...]] = ('dead_zone', 'saturation_velocity', 'curvature',
                                       'exponent')

    dead_zone: tuple[float, float]
    saturation_velocity: tuple[float, float]
    curvature: tuple[float, float]
    exponent: tuple[float, float]

    def __post_init__(self) -> None:
        check_dead_zone(self.dead_zone)
        check_saturation_velocity(self.saturation_velocity)
        check_positive_pair('curvature', self.curvature)
        check_positive_pair('exponent', self.exponent)

    def rate(self, v: FloatArray) -> FloatArray:
        """Angular velocity (deg/s) for steady commands ``v`` (:meth:`StaticMap.rate`)."""
        return power_sat_rate(v, self.saturation_velocity[0], self.curvature[0],
                              self.exponent[0], self.dead_zone[0], self.saturation_velocity[1],
                              self.curvature[1], self.exponent[1], self.dead_zone[1])

    def shifted(self, shift: tuple[float, float]) -> PowerSatMap:
        """Return the map with ``shift`` added to its lower and upper edge, input units."""
        return replace(self, dead_zone=(self.dead_zone[0] + shift[0],
                                        self.dead_zone[1] + shift[1]))

    def to_mapping(self) -> dict[str, float | list[float]]:
        """Return the model-file keys of this map."""
        return {key: list(getattr(self, key)) for key in self.keys}

    @classmethod
    def from_mapping(cls, data: Document) -> PowerSatMap:
        """Build the map from model-file keys (already checked for presence)."""
        return cls(
            dead_zone=require_ordered_pair(data['dead_zone'], 'dead_zone', strict=False),
            saturation_velocity=require_pair(data['saturation_velocity'], 'saturation_velocity'),
            curvature=require_pair(data['curvature'], 'curvature'),
            exponent=require_pair(data['exponent'], 'exponent'),
        )

"""
The exponential SDP map, eq. (5) of West et al. (2018) as corrected in methods 3.1, and its chords.

:func:`sdp_rate` is the one coding of the equation; :func:`linearise` is eq. (6) (methods 3.3).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
import math
from typing import ClassVar, Literal

from hydro_sdp.core.arrays import FloatArray
from hydro_sdp.core.errors import ConfigurationError, ModelFileError
from hydro_sdp.core.model.static_maps.protocol import (
    check_dead_zone, check_positive_pair, check_saturation_velocity, MapKind)
from hydro_sdp.core.model.static_maps.sdp_dz import SdpDzMap
from hydro_sdp.core.model.timing import SamplePeriod
from hydro_sdp.core.validation import Document, require_ordered_pair, require_pair
import numpy as np

#: Fraction of the saturation speed where the IDZ chord meets an exponential map.
CHORD_SPEED_FRACTION = 2.0 / 3.0


def sdp_rate(v: FloatArray | float, vn: float, cn: float, a3: float, vp: float, cp: float,
             a6: float) -> FloatArray:
    """
    Evaluate eq. (5): ``vn (1 - exp(cn (v - a3)))`` below ``a3``, 0 inside, ``vp (..)`` above.

    ``v``: commands, input units.
    ``vn``, ``vp``: negative and positive saturation speeds (``vn < 0 < vp``); the result is in
    their unit (deg/s, or deg per sample for the paper's ``alpha_1``, ``alpha_4``).
    ``cn``, ``cp``: curvatures, 1/input unit.
    ``a3``, ``a6``: lower and upper dead-zone edges, input units.
    """
    v = np.asarray(v, dtype=np.float64)
    if v.size == 1:
        # A simulation's step asks for one command at a time, where numpy's overhead is
        # most of the cost: the same operations on Python floats.
        x = float(v.flat[0])
        one = vn * -math.expm1(cn * min(x - a3, 0.0)) + vp * -math.expm1(-cp * max(x - a6, 0.0))
        return np.full(v.shape, one)[()]
    # Clipping the exponent's argument at zero keeps the inactive branch finite.
    below = vn * -np.expm1(cn * np.minimum(v - a3, 0.0))
    above = vp * -np.expm1(-cp * np.maximum(v - a6, 0.0))
    return below + above


@dataclass(frozen=True)
class SdpMap:
    """
    Exponential SDP map with dead-zone and asymmetric saturation (kind ``sdp``, methods 3.1).

    Parameters
    ----------
    dead_zone : tuple[float, float]
        Edges ``(a3, a6)`` in input units.
    saturation_velocity : tuple[float, float]
        Speeds ``(vn, vp)`` approached for large commands, deg/s; ``vn < 0 < vp``.
    curvature : tuple[float, float]
        ``(cn, cp)``, 1/input unit.

    """

    kind: ClassVar[MapKind] = 'sdp'
    keys: ClassVar[tuple[str, ...]] = ('dead_zone', 'saturation_velocity', 'curvature')

    dead_zone: tuple[float, float]
    saturation_velocity: tuple[float, float]
    curvature: tuple[float, float]

    def __post_init__(self) -> None:
        check_dead_zone(self.dead_zone)
        check_saturation_velocity(self.saturation_velocity)
        check_positive_pair('curvature', self.curvature)

    def rate(self, v: FloatArray) -> FloatArray:
        """Angular velocity (deg/s) for steady commands ``v`` (:meth:`StaticMap.rate`)."""
        low, high = self.dead_zone
        c_neg, c_pos = self.curvature
        v_neg, v_pos = self.saturation_velocity
        return sdp_rate(v, v_neg, c_neg, low, v_pos, c_pos, high)

    def shifted(self, shift: tuple[float, float]) -> SdpMap:
        """Return the map with ``shift`` added to its lower and upper edge, input units."""
        return replace(self, dead_zone=(self.dead_zone[0] + shift[0],
                                        self.dead_zone[1] + shift[1]))

    def to_mapping(self) -> dict[str, float | list[float]]:
        """Return the model-file keys of this map."""
        return {
            'dead_zone': list(self.dead_zone),
            'saturation_velocity': list(self.saturation_velocity),
            'curvature': list(self.curvature),
        }

    @classmethod
    def from_mapping(cls, data: Document) -> SdpMap:
        """Build the map from model-file keys (already checked for presence)."""
        return cls(
            dead_zone=require_ordered_pair(data['dead_zone'], 'dead_zone', strict=False),
            saturation_velocity=require_pair(data['saturation_velocity'], 'saturation_velocity'),
            curvature=require_pair(data['curvature'], 'curvature'),
        )

    def alpha(self, dt: SamplePeriod) -> tuple[float, float, float, float, float, float]:
        """Return the paper's ``(vn dt, cn, a3, vp dt, cp, a6)`` at sample period ``dt`` (s)."""
        return (self.saturation_velocity[0] * dt, self.curvature[0], self.dead_zone[0],
                self.saturation_velocity[1] * dt, self.curvature[1], self.dead_zone[1])

    @classmethod
    def from_alpha(cls, alpha: tuple[float, ...], dt: SamplePeriod, *,
                   convention: Literal['signed', 'magnitude'] = 'signed') -> SdpMap:
        """
        Build the map from the paper's ``alpha_1..alpha_6`` at sample period ``dt``.

        ``alpha``: ``(a1, a2, a3, a4, a5, a6)``; ``a1`` and ``a4`` in deg per sample.
        ``dt``: sample period the coefficients refer to, s.
        ``convention``: ``signed`` (``a1 < 0``) or ``magnitude`` (Table 1's ``a1 > 0``; methods
        2.3).
        """
        a1, a2, a3, a4, a5, a6 = (float(a) for a in alpha)
        if convention == 'magnitude':
            a1 = -abs(a1)
        elif convention != 'signed':
            raise ModelFileError(f"alpha convention must be 'signed' or 'magnitude', "
                                 f'got {convention!r}')
        return cls(dead_zone=(a3, a6), saturation_velocity=(a1 / dt, a4 / dt),
                   curvature=(a2, a5))


def chord_commands(sdp: SdpMap, fraction: float = CHORD_SPEED_FRACTION) -> tuple[float, float]:
    """Commands ``(v_min, v_max)`` where an exponential map reaches ``fraction`` of saturation."""
    if not 0.0 < fraction < 1.0:
        raise ConfigurationError(f'the chord speed fraction must be in (0, 1), got {fraction}')
    distance = -math.log(1.0 - fraction)
    return (sdp.dead_zone[0] - distance / sdp.curvature[0],
            sdp.dead_zone[1] + distance / sdp.curvature[1])


def linearise(sdp: SdpMap, v_min: float, v_max: float) -> SdpDzMap:
    """
    Chord approximation of an SDP map between its edges and two commands (eq. (6)).

    ``v_min``: command below the lower edge where the chord meets the curve.
    ``v_max``: command above the upper edge where the chord meets the curve.
    Returns: dead-zone map with the same edges and the chord slopes (deg/s per unit).
    """
    low, high = sdp.dead_zone
    if not v_min < low or not v_max > high:
        raise ModelFileError(
            f'linearisation needs v_min < {low} and v_max > {high}, got {v_min} and {v_max}')
    rates = sdp.rate(np.array([v_min, v_max]))
    return SdpDzMap(dead_zone=sdp.dead_zone,
                    slope=(float(rates[0] / (v_min - low)), float(rates[1] / (v_max - high))))

"""
Static maps from the valve command to the joint's angular velocity.

A hydraulic joint is an integrator whose speed is a static function of the
delayed command: ``y_k = y_{k-1} + dt * rate(v_{k-tau})``. Each class here is
one family of that function (one ``kind`` of the model file), with its
parameters in rate units (deg/s) so that the same map serves every sample
period. The maths is eq. (5) of West et al. (2018) as corrected in docs/methods.md
section 3.1, and its dead-zone linearisation eq. (6).

"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar, Mapping, Union

from hydro_sdp.core._validate import require_float, require_ordered_pair, require_pair
from hydro_sdp.core.arrays import FloatArray
from hydro_sdp.core.errors import ModelFileError
import numpy as np


@dataclass(frozen=True)
class SdpMap:
    """
    Exponential SDP map with dead-zone and asymmetric saturation (kind ``sdp``).

    ``rate(v) = vn (1 - exp(cn (v - a3)))`` below the dead-zone, ``0`` inside it
    and ``vp (1 - exp(-cp (v - a6)))`` above it.

    Parameters
    ----------
    dead_zone : tuple[float, float]
        Edges ``(a3, a6)`` in input units.
    saturation_velocity : tuple[float, float]
        Speeds ``(vn, vp)`` approached for large commands, deg/s; ``vn < 0 < vp``.
    curvature : tuple[float, float]
        ``(cn, cp)``, 1/input unit: how fast each branch approaches its saturation.

    """

    kind: ClassVar[str] = 'sdp'
    keys: ClassVar[tuple[str, ...]] = ('dead_zone', 'saturation_velocity', 'curvature')

    dead_zone: tuple[float, float]
    saturation_velocity: tuple[float, float]
    curvature: tuple[float, float]

    def __post_init__(self) -> None:
        _check_dead_zone(self.dead_zone)
        negative, positive = self.saturation_velocity
        if not negative < 0.0 < positive:
            raise ModelFileError(
                "key 'saturation_velocity': expected [negative, positive] deg/s, "
                f'got [{negative}, {positive}]')
        if min(self.curvature) <= 0.0:
            raise ModelFileError(
                f"key 'curvature': both values must be > 0, got {list(self.curvature)}")

    def rate(self, v: FloatArray) -> FloatArray:
        """
        Angular velocity (deg/s) for steady commands ``v``.

        Parameters
        ----------
        v : FloatArray
            Commands in input units.

        Returns
        -------
        FloatArray
            Velocities, same shape as ``v``.

        """
        v = np.asarray(v, dtype=np.float64)
        low, high = self.dead_zone
        c_neg, c_pos = self.curvature
        v_neg, v_pos = self.saturation_velocity
        # Clipping the exponent's argument at zero keeps the inactive branch finite.
        below = v_neg * -np.expm1(c_neg * np.minimum(v - low, 0.0))
        above = v_pos * -np.expm1(-c_pos * np.maximum(v - high, 0.0))
        return below + above

    def to_mapping(self) -> dict[str, Any]:
        """Return the model-file keys of this map."""
        return {
            'dead_zone': list(self.dead_zone),
            'saturation_velocity': list(self.saturation_velocity),
            'curvature': list(self.curvature),
        }

    @classmethod
    def from_mapping(cls, data: Mapping[str, Any]) -> SdpMap:
        """Build the map from model-file keys (already checked for presence)."""
        return cls(
            dead_zone=require_ordered_pair(data['dead_zone'], 'dead_zone', strict=False),
            saturation_velocity=require_pair(data['saturation_velocity'], 'saturation_velocity'),
            curvature=require_pair(data['curvature'], 'curvature'),
        )

    def alpha(self, dt: float) -> tuple[float, float, float, float, float, float]:
        """
        Return the paper's coefficients ``alpha_1..alpha_6`` at sample period ``dt``.

        Parameters
        ----------
        dt : float
            Sample period, s.

        Returns
        -------
        tuple of six floats
            ``(vn dt, cn, a3, vp dt, cp, a6)``.

        """
        return (self.saturation_velocity[0] * dt, self.curvature[0], self.dead_zone[0],
                self.saturation_velocity[1] * dt, self.curvature[1], self.dead_zone[1])

    @classmethod
    def from_alpha(cls, alpha: tuple[float, ...], dt: float, *,
                   convention: str = 'signed') -> SdpMap:
        """
        Build the map from the paper's ``alpha_1..alpha_6`` at sample period ``dt``.

        Parameters
        ----------
        alpha : tuple of six floats
            ``(a1, a2, a3, a4, a5, a6)``; ``a1`` and ``a4`` in deg per sample.
        dt : float
            Sample period the coefficients refer to, s.
        convention : str
            ``signed`` (the paper's text: ``a1 < 0``) or ``magnitude`` (its Table 1:
            ``a1 > 0`` is the size of the negative saturation; docs/methods.md section 2.3).

        Returns
        -------
        SdpMap
            The equivalent rate-based map.

        """
        a1, a2, a3, a4, a5, a6 = (float(a) for a in alpha)
        if convention == 'magnitude':
            a1 = -abs(a1)
        elif convention != 'signed':
            raise ModelFileError(f"alpha convention must be 'signed' or 'magnitude', "
                                 f'got {convention!r}')
        return cls(dead_zone=(a3, a6), saturation_velocity=(a1 / dt, a4 / dt),
                   curvature=(a2, a5))


@dataclass(frozen=True)
class SdpDzMap:
    """
    Piecewise-linear dead-zone map (kind ``sdp_dz``, eq. (6) of West et al.).

    Parameters
    ----------
    dead_zone : tuple[float, float]
        Edges ``(a3, a6)`` in input units.
    slope : tuple[float, float]
        ``(s_n, s_p)``, deg/s per input unit beyond each edge.

    """

    kind: ClassVar[str] = 'sdp_dz'
    keys: ClassVar[tuple[str, ...]] = ('dead_zone', 'slope')

    dead_zone: tuple[float, float]
    slope: tuple[float, float]

    def __post_init__(self) -> None:
        _check_dead_zone(self.dead_zone)
        if min(self.slope) <= 0.0:
            raise ModelFileError(
                f"key 'slope': both values must be > 0, got {list(self.slope)}")

    def rate(self, v: FloatArray) -> FloatArray:
        """
        Angular velocity (deg/s) for steady commands ``v``.

        Parameters
        ----------
        v : FloatArray
            Commands in input units.

        Returns
        -------
        FloatArray
            Velocities, same shape as ``v``.

        """
        v = np.asarray(v, dtype=np.float64)
        low, high = self.dead_zone
        return self.slope[0] * np.minimum(v - low, 0.0) + self.slope[1] * np.maximum(v - high, 0.0)

    def to_mapping(self) -> dict[str, Any]:
        """Return the model-file keys of this map."""
        return {'dead_zone': list(self.dead_zone), 'slope': list(self.slope)}

    @classmethod
    def from_mapping(cls, data: Mapping[str, Any]) -> SdpDzMap:
        """Build the map from model-file keys (already checked for presence)."""
        return cls(dead_zone=require_ordered_pair(data['dead_zone'], 'dead_zone', strict=False),
                   slope=require_pair(data['slope'], 'slope'))


@dataclass(frozen=True)
class LinearMap:
    """
    Linear integrator gain (kind ``linear``, eq. (2) of West et al. with a1 = -1).

    Parameters
    ----------
    gain : float
        deg/s per input unit.

    """

    kind: ClassVar[str] = 'linear'
    keys: ClassVar[tuple[str, ...]] = ('gain',)

    gain: float

    def __post_init__(self) -> None:
        if not self.gain > 0.0:
            raise ModelFileError(f"key 'gain': must be > 0, got {self.gain}")

    @property
    def dead_zone(self) -> None:
        """Return None: a linear map has no dead-zone."""
        return None

    def rate(self, v: FloatArray) -> FloatArray:
        """
        Angular velocity (deg/s) for steady commands ``v``.

        Parameters
        ----------
        v : FloatArray
            Commands in input units.

        Returns
        -------
        FloatArray
            Velocities, same shape as ``v``.

        """
        return self.gain * np.asarray(v, dtype=np.float64)

    def to_mapping(self) -> dict[str, Any]:
        """Return the model-file keys of this map."""
        return {'gain': self.gain}

    @classmethod
    def from_mapping(cls, data: Mapping[str, Any]) -> LinearMap:
        """Build the map from model-file keys (already checked for presence)."""
        return cls(gain=require_float(data['gain'], 'gain'))


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

    kind: ClassVar[str] = 'pwl'
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
        """
        Angular velocity (deg/s) for steady commands ``v``.

        Parameters
        ----------
        v : FloatArray
            Commands in input units.

        Returns
        -------
        FloatArray
            Velocities, same shape as ``v``.

        """
        return np.interp(np.asarray(v, dtype=np.float64), self.knots, self.speeds)

    def to_mapping(self) -> dict[str, Any]:
        """Return the model-file keys of this map."""
        return {'knots': list(self.knots), 'speeds': list(self.speeds)}

    @classmethod
    def from_mapping(cls, data: Mapping[str, Any]) -> PwlMap:
        """Build the map from model-file keys (already checked for presence)."""
        return cls(knots=_float_list(data['knots'], 'knots'),
                   speeds=_float_list(data['speeds'], 'speeds'))


@dataclass(frozen=True)
class PolyMap:
    """
    Polynomial gain map (kind ``poly``), the second paper's ``b(v)`` per direction.

    ``rate(v) = v b(v)`` with ``b(v) = sum_i c_i v^i`` from ``gain_negative`` for
    ``v < 0`` and ``gain_positive`` for ``v > 0``; commands are clipped to
    ``command_range``, the range the polynomials were fitted on.

    Parameters
    ----------
    gain_negative : tuple[float, ...]
        Coefficients ``c_0, c_1, ..`` for negative commands, deg/s per input unit.
    gain_positive : tuple[float, ...]
        Coefficients for positive commands.
    command_range : tuple[float, float]
        ``(v_min, v_max)`` with ``v_min < 0 < v_max``.

    """

    kind: ClassVar[str] = 'poly'
    keys: ClassVar[tuple[str, ...]] = ('gain_negative', 'gain_positive', 'command_range')

    gain_negative: tuple[float, ...]
    gain_positive: tuple[float, ...]
    command_range: tuple[float, float]

    def __post_init__(self) -> None:
        for name in ('gain_negative', 'gain_positive'):
            values = tuple(float(x) for x in getattr(self, name))
            if not values or not all(np.isfinite(values)):
                raise ModelFileError(f'key {name!r}: needs finite coefficients')
            object.__setattr__(self, name, values)
        low, high = (float(x) for x in self.command_range)
        if not low < 0.0 < high:
            raise ModelFileError(f"key 'command_range': expected [negative, positive], "
                                 f'got [{low}, {high}]')
        object.__setattr__(self, 'command_range', (low, high))

    @property
    def dead_zone(self) -> None:
        """Return None: the polynomial map has no explicit dead-zone."""
        return None

    def rate(self, v: FloatArray) -> FloatArray:
        """
        Angular velocity (deg/s) for steady commands ``v``.

        Parameters
        ----------
        v : FloatArray
            Commands in input units.

        Returns
        -------
        FloatArray
            Velocities, same shape as ``v``.

        """
        v = np.clip(np.asarray(v, dtype=np.float64), *self.command_range)
        negative = np.polynomial.polynomial.polyval(v, self.gain_negative)
        positive = np.polynomial.polynomial.polyval(v, self.gain_positive)
        return v * np.where(v < 0.0, negative, positive)

    def to_mapping(self) -> dict[str, Any]:
        """Return the model-file keys of this map."""
        return {'gain_negative': list(self.gain_negative),
                'gain_positive': list(self.gain_positive),
                'command_range': list(self.command_range)}

    @classmethod
    def from_mapping(cls, data: Mapping[str, Any]) -> PolyMap:
        """Build the map from model-file keys (already checked for presence)."""
        return cls(gain_negative=_float_list(data['gain_negative'], 'gain_negative'),
                   gain_positive=_float_list(data['gain_positive'], 'gain_positive'),
                   command_range=require_ordered_pair(data['command_range'], 'command_range'))


StaticMap = Union[SdpMap, SdpDzMap, LinearMap, PwlMap, PolyMap]

#: Map classes by the model file's ``kind``.
MAP_KINDS: dict[str, type] = {
    cls.kind: cls for cls in (SdpMap, SdpDzMap, LinearMap, PwlMap, PolyMap)
}


def _float_list(values: Any, key: str) -> tuple[float, ...]:
    if not isinstance(values, (list, tuple)):
        raise ModelFileError(f'key {key!r}: expected a list of numbers')
    return tuple(require_float(value, f'{key}[{i}]') for i, value in enumerate(values))


def linearise(sdp: SdpMap, v_min: float, v_max: float) -> SdpDzMap:
    """
    Chord approximation of an SDP map between its edges and two commands (eq. (6)).

    Parameters
    ----------
    sdp : SdpMap
        The exponential map.
    v_min : float
        Command below the lower edge where the chord meets the curve.
    v_max : float
        Command above the upper edge where the chord meets the curve.

    Returns
    -------
    SdpDzMap
        Dead-zone map with the same edges and the chord slopes (deg/s per unit).

    """
    low, high = sdp.dead_zone
    if not v_min < low or not v_max > high:
        raise ModelFileError(
            f'linearisation needs v_min < {low} and v_max > {high}, got {v_min} and {v_max}')
    rates = sdp.rate(np.array([v_min, v_max]))
    return SdpDzMap(dead_zone=sdp.dead_zone,
                    slope=(float(rates[0] / (v_min - low)), float(rates[1] / (v_max - high))))


def _check_dead_zone(dead_zone: tuple[float, float]) -> None:
    if dead_zone[0] > dead_zone[1]:
        raise ModelFileError(
            f"key 'dead_zone': lower edge {dead_zone[0]} is above upper edge {dead_zone[1]}")

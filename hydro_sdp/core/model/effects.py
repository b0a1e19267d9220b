"""
Effects: composable additions to a joint model, one per vocabulary word (methods 3.6).

Each is a frozen dataclass whose fields are its model-file parameters, e.g.
``effects: {valve_lag: {time_constant: 0.08}}``.
"""

from __future__ import annotations

from bisect import bisect_right
from dataclasses import asdict, dataclass, fields, MISSING
import math
from typing import Any, ClassVar, Mapping, Union

from hydro_sdp.core.arrays import FloatArray
from hydro_sdp.core.errors import ModelFileError
from hydro_sdp.core.model.pump_and_load import FlowSharing, LoadDependence
from hydro_sdp.core.validation import require_float, require_float_list
import numpy as np


@dataclass(frozen=True)
class ValveLag:
    """
    First-order lag between the static map and the joint speed (methods 3.6).

    Parameters
    ----------
    time_constant : float
        Lag time constant, s (> 0).

    """

    name: ClassVar[str] = 'valve_lag'
    time_constant: float

    def __post_init__(self) -> None:
        if not self.time_constant > 0.0:
            raise ModelFileError(
                f"key 'effects.valve_lag.time_constant': must be > 0, got {self.time_constant}")


@dataclass(frozen=True)
class Backlash:
    """
    Play between actuator and angle sensor (a play operator on the output).

    Parameters
    ----------
    play : float
        Total play ``2b`` in degrees (>= 0).

    """

    name: ClassVar[str] = 'backlash'
    play: float

    def __post_init__(self) -> None:
        if self.play < 0.0:
            raise ModelFileError(f"key 'effects.backlash.play': must be >= 0, got {self.play}")


@dataclass(frozen=True)
class AngleDependentVelocity:
    """
    Speed ``w + amplitude |w| cos(y + phase)``: linkage geometry, gravity load (methods 3.6).

    Parameters
    ----------
    amplitude : float
        Relative size of the effect, ``|amplitude| < 1``.
    phase : float
        Angle offset, degrees.

    """

    name: ClassVar[str] = 'angle_dependent_velocity'
    amplitude: float
    phase: float = 0.0

    def __post_init__(self) -> None:
        if not abs(self.amplitude) < 1.0:
            raise ModelFileError(
                "key 'effects.angle_dependent_velocity.amplitude': must be inside (-1, 1), "
                f'got {self.amplitude}')


@dataclass(frozen=True)
class Oscillation:
    """
    The link rings on the oil column: a second-order mode between actuator and link (methods 3.6).

    Parameters
    ----------
    frequency : float
        Natural frequency of the mode, Hz (> 0).
    damping : float
        Damping ratio, inside (0, 1).

    """

    name: ClassVar[str] = 'oscillation'
    frequency: float
    damping: float

    def __post_init__(self) -> None:
        if not (math.isfinite(self.frequency) and self.frequency > 0.0):
            raise ModelFileError(
                f"key 'effects.oscillation.frequency': must be > 0 Hz, got {self.frequency}")
        if not 0.0 < self.damping < 1.0:
            raise ModelFileError(
                f"key 'effects.oscillation.damping': must be inside (0, 1), got {self.damping}")


@dataclass(frozen=True)
class DirectionDependentDelay:
    """
    Separate pure delays for the two directions of motion; they replace the model's ``delay``.

    Parameters
    ----------
    positive : float
        Delay of motion in the positive direction, s (>= 0).
    negative : float
        Delay of motion in the negative direction, s (>= 0).

    """

    name: ClassVar[str] = 'direction_dependent_delay'
    positive: float
    negative: float

    def __post_init__(self) -> None:
        for label, value in (('positive', self.positive), ('negative', self.negative)):
            if value < 0.0:
                raise ModelFileError(
                    f"key 'effects.direction_dependent_delay.{label}': must be >= 0, "
                    f'got {value}')


@dataclass(frozen=True)
class StrokeGeometry:
    """
    Speed scaled by a smooth factor of the angle along the stroke (methods 3.6).

    Parameters
    ----------
    knots : tuple[float, ...]
        Angles, degrees, strictly increasing (two or more).
    factors : tuple[float, ...]
        Shared speed factor at each knot (> 0).
    asymmetry : tuple[float, ...]
        Per-direction part at each knot, inside (-1, 1), or empty for none.
    cushion : float
        Length of the end cushions, degrees (>= 0, 0: none).
    cushion_factor : float
        Speed factor at the very end of a cushion, in (0, 1].

    """

    name: ClassVar[str] = 'stroke_geometry'
    knots: tuple[float, ...]
    factors: tuple[float, ...]
    asymmetry: tuple[float, ...] = ()
    cushion: float = 0.0
    cushion_factor: float = 1.0

    def __post_init__(self) -> None:
        key = "key 'effects.stroke_geometry"
        knots = tuple(float(x) for x in self.knots)
        factors = tuple(float(x) for x in self.factors)
        asymmetry = tuple(float(x) for x in self.asymmetry)
        if len(knots) < 2 or len(factors) != len(knots) or len(asymmetry) not in (0, len(knots)):
            raise ModelFileError(f"{key}': knots and factors (and asymmetry, if given) need "
                                 'two or more values each, of equal number')
        if not np.all(np.isfinite(knots + factors + asymmetry)) or np.any(np.diff(knots) <= 0.0):
            raise ModelFileError(f"{key}.knots': must be finite and strictly increasing")
        if min(factors) <= 0.0:
            raise ModelFileError(f"{key}.factors': must be > 0, got {list(factors)}")
        if asymmetry and max(abs(a) for a in asymmetry) >= 1.0:
            raise ModelFileError(f"{key}.asymmetry': must be inside (-1, 1)")
        if self.cushion < 0.0 or not 0.0 < self.cushion_factor <= 1.0:
            raise ModelFileError(f"{key}': cushion must be >= 0 and cushion_factor in (0, 1], "
                                 f'got {self.cushion} and {self.cushion_factor}')
        object.__setattr__(self, 'knots', knots)
        object.__setattr__(self, 'factors', factors)
        object.__setattr__(self, 'asymmetry', asymmetry)

    def factor_at(self, angle: float, speed: float) -> float:
        """Return the speed factor at ``angle`` (degrees) for motion of sign ``speed``."""
        knots = self.knots
        if angle <= knots[0]:
            index, weight = 0, 0.0
        elif angle >= knots[-1]:
            index, weight = len(knots) - 2, 1.0
        else:
            index = bisect_right(knots, angle) - 1
            weight = (angle - knots[index]) / (knots[index + 1] - knots[index])
        factor = self.factors[index] + weight * (self.factors[index + 1] - self.factors[index])
        direction = 1.0 if speed > 0.0 else -1.0 if speed < 0.0 else 0.0
        if self.asymmetry:
            part = self.asymmetry[index] + weight * (self.asymmetry[index + 1] -
                                                     self.asymmetry[index])
            factor *= 1.0 + direction * part
        if self.cushion > 0.0 and direction != 0.0:
            distance = knots[-1] - angle if direction > 0.0 else angle - knots[0]
            share = min(max(distance / self.cushion, 0.0), 1.0)
            factor *= self.cushion_factor + (1.0 - self.cushion_factor) * share
        return factor

    def factor(self, angles: FloatArray, speeds: FloatArray) -> FloatArray:
        """Return :meth:`factor_at` for arrays (same operations in the same order)."""
        angle = np.asarray(angles, dtype=np.float64)
        speed = np.asarray(speeds, dtype=np.float64)
        knots = np.asarray(self.knots)
        inside = np.clip(np.searchsorted(knots, angle, side='right') - 1, 0, knots.size - 2)
        index = np.where(angle <= knots[0], 0,
                         np.where(angle >= knots[-1], knots.size - 2, inside))
        span = knots[index + 1] - knots[index]
        weight = np.where(angle <= knots[0], 0.0, np.where(angle >= knots[-1], 1.0,
                                                           (angle - knots[index]) / span))
        factors = np.asarray(self.factors)
        factor = factors[index] + weight * (factors[index + 1] - factors[index])
        direction = np.sign(speed)
        if self.asymmetry:
            table = np.asarray(self.asymmetry)
            part = table[index] + weight * (table[index + 1] - table[index])
            factor = factor * (1.0 + direction * part)
        if self.cushion > 0.0:
            distance = np.where(direction > 0.0, knots[-1] - angle, angle - knots[0])
            share = np.minimum(np.maximum(distance / self.cushion, 0.0), 1.0)
            cushioned = factor * (self.cushion_factor + (1.0 - self.cushion_factor) * share)
            factor = np.where(direction != 0.0, cushioned, factor)
        return factor


Effect = Union[ValveLag, Backlash, AngleDependentVelocity, DirectionDependentDelay,
               StrokeGeometry, FlowSharing, LoadDependence, Oscillation]

#: Effect classes by vocabulary word, in the order the simulation applies them.
EFFECT_TYPES: dict[str, type[Effect]] = {
    cls.name: cls
    for cls in (DirectionDependentDelay, ValveLag, FlowSharing, LoadDependence, StrokeGeometry,
                AngleDependentVelocity, Oscillation, Backlash)
}


def effect_from_mapping(name: str, params: object) -> Effect:
    """Build one validated effect from its model-file entry (``name`` in :data:`EFFECT_TYPES`)."""
    if name not in EFFECT_TYPES:
        known = ', '.join(EFFECT_TYPES)
        raise ModelFileError(f"key 'effects': unknown effect {name!r} (known: {known})")
    cls = EFFECT_TYPES[name]
    if not isinstance(params, Mapping):
        raise ModelFileError(f"key 'effects.{name}': expected a mapping of parameters")
    names = [field.name for field in fields(cls)]
    unknown = sorted(set(params) - set(names))
    if unknown:
        raise ModelFileError(f"key 'effects.{name}': unknown parameter {unknown[0]!r} "
                             f"(parameters: {', '.join(names)})")
    # Each value is checked against its own field's type below; mypy cannot pair them.
    values: dict[str, Any] = {}
    for field in fields(cls):
        if field.name in params:
            key = f'effects.{name}.{field.name}'
            value = params[field.name]
            if str(field.type) == 'tuple[str, ...]':
                if not isinstance(value, list) or not all(isinstance(x, str) for x in value):
                    raise ModelFileError(f'key {key!r}: expected a list of names')
                values[field.name] = tuple(value)
            elif str(field.type).startswith('tuple'):
                values[field.name] = require_float_list(value, key)
            else:
                values[field.name] = require_float(value, key)
        elif field.default is MISSING:
            raise ModelFileError(f"key 'effects.{name}': missing parameter {field.name!r}")
    return cls(**values)


def effect_to_mapping(effect: Effect) -> dict[str, float | list[float] | list[str]]:
    """Return the model-file parameters of ``effect`` (lists for the tables)."""
    out: dict[str, float | list[float] | list[str]] = {}
    for key, value in asdict(effect).items():
        if isinstance(value, tuple):
            out[key] = [str(x) for x in value] if key == 'records' else [float(x) for x in value]
        else:
            out[key] = float(value)
    return out

"""
Effects: composable additions to a joint model.

Each effect is one word of the discrepancy vocabulary (docs/interfaces.md section 5)
that cannot be expressed by the base parameters of a static map. An effect is a
frozen dataclass whose fields are its parameters in the model file's
``effects`` mapping, e.g. ``effects: {valve_lag: {time_constant: 0.08}}``. The
simulation in :mod:`hydro_sdp.core.simulation` applies them.

"""

from __future__ import annotations

from dataclasses import asdict, dataclass, fields, MISSING
from typing import Any, ClassVar, Mapping, Union

from hydro_sdp.core._validate import require_float
from hydro_sdp.core.errors import ModelFileError


@dataclass(frozen=True)
class ValveLag:
    """
    First-order lag between the static map and the joint speed.

    ``w_k = p w_{k-1} + (1 - p) rate(v_{k-tau})`` with ``p = exp(-dt / time_constant)``;
    the joint integrates ``w``.

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

    After a reversal the measured angle stands still until the actuator has
    taken up the play, then follows it again.

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
    Speed that depends on the joint angle (linkage geometry, gravity load).

    The speed becomes ``w + amplitude |w| cos(y + phase)``, i.e. motion is faster
    by the factor ``1 + amplitude cos(y + phase)`` in the positive direction and
    ``1 - amplitude cos(y + phase)`` in the negative one.

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
class DirectionDependentDelay:
    """
    Different pure delays for the two directions of motion.

    The positive part of the speed is delayed by ``positive`` seconds and the
    negative part by ``negative`` seconds; they replace the model's ``delay``.

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


Effect = Union[ValveLag, Backlash, AngleDependentVelocity, DirectionDependentDelay]

#: Effect classes by vocabulary word, in the order the simulation applies them.
EFFECT_TYPES: dict[str, type[Effect]] = {
    cls.name: cls
    for cls in (DirectionDependentDelay, ValveLag, AngleDependentVelocity, Backlash)
}


def effect_from_mapping(name: str, params: Any) -> Effect:
    """
    Build one effect from its model-file entry.

    Parameters
    ----------
    name : str
        Vocabulary word, a key of :data:`EFFECT_TYPES`.
    params : Any
        The mapping of parameters read from the file.

    Returns
    -------
    Effect
        The validated effect.

    """
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
    values = {}
    for field in fields(cls):
        if field.name in params:
            values[field.name] = require_float(params[field.name], f'effects.{name}.{field.name}')
        elif field.default is MISSING:
            raise ModelFileError(f"key 'effects.{name}': missing parameter {field.name!r}")
    return cls(**values)


def effect_to_mapping(effect: Effect) -> dict[str, float]:
    """Return the model-file parameters of ``effect``."""
    return {key: float(value) for key, value in asdict(effect).items()}

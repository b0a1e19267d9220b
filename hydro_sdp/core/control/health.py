"""The health of one controlled or identified joint, as ``/diagnostics`` reports it."""

from __future__ import annotations

from dataclasses import dataclass, field
import math
from typing import Mapping

#: Levels of ``diagnostic_msgs/DiagnosticStatus``.
OK, WARN, ERROR = 0, 1, 2


@dataclass(frozen=True)
class JointSnapshot:
    """
    What a node knows about one joint at a report.

    Attributes
    ----------
    feedback_age : float or None
        Time since the last valid feedback sample, s (``None``: none yet).
    stale_after : float
        Age beyond which feedback counts as stale, s.
    refused : int
        Feedback samples refused since the last report.
    clamped : bool
        Whether the set-point in force was clamped to the end stops.
    active : bool
        Whether the node is commanding (False: a lifecycle node not active).
    setpoint, angle : float or None
        Set-point and last measured angle, degrees.
    command : float or None
        Last valve command, input units.
    idz_edges : tuple[float, float] or None
        IDZ edges in use, input units.
    estimates : mapping of str to (float, float)
        Estimated values and their standard deviations, by name (units in the name).

    """

    joint: str
    feedback_age: float | None
    stale_after: float
    watchdog_closed: bool = False
    refused: int = 0
    clamped: bool = False
    recalibration_needed: bool = False
    active: bool = True
    setpoint: float | None = None
    angle: float | None = None
    command: float | None = None
    idz_edges: tuple[float, float] | None = None
    estimates: Mapping[str, tuple[float, float]] = field(default_factory=dict)


@dataclass(frozen=True)
class HealthStatus:
    """
    A joint's status: level (:data:`OK`, :data:`WARN`, :data:`ERROR`), message, key-values.

    Attributes
    ----------
    message : str
        One line: what is wrong, or ``ok``.

    """

    level: int
    message: str
    values: tuple[tuple[str, str], ...]


def _number(value: float | None) -> str:
    return 'none' if value is None or not math.isfinite(value) else f'{value:.6g}'


def _problems(snapshot: JointSnapshot) -> tuple[int, list[str]]:
    if not snapshot.active:
        return OK, []
    if snapshot.watchdog_closed:
        age = snapshot.feedback_age
        since = 'ever' if age is None else f'{age:.2f} s'
        return ERROR, [f'watchdog closed the valve: no valid feedback for {since}']
    warnings = []
    if snapshot.feedback_age is None:
        warnings.append('no feedback yet')
    elif snapshot.feedback_age > snapshot.stale_after:
        warnings.append(f'feedback stale ({snapshot.feedback_age:.3f} s old)')
    if snapshot.refused:
        warnings.append(f'feedback refused ({snapshot.refused} samples)')
    if snapshot.recalibration_needed:
        warnings.append('recalibration needed')
    if snapshot.clamped:
        warnings.append('set-point clamped to the end stops')
    return (WARN if warnings else OK), warnings


def joint_health(snapshot: JointSnapshot) -> HealthStatus:
    """
    Return the status of one joint from a snapshot of its state.

    ``snapshot``: the joint's state at the report.
    Returns: level, message (the problems joined by ``; ``, ``ok``, or ``inactive``) and
    key-values: ``active``, ``feedback age [s]``, ``set-point [deg]``, ``angle [deg]``,
    ``error [deg]`` (set-point less angle), ``command``, the IDZ edges when known, then each
    estimate and ``<name> std``.
    """
    level, problems = _problems(snapshot)
    message = '; '.join(problems) if problems else ('ok' if snapshot.active else 'inactive')
    setpoint, angle = snapshot.setpoint, snapshot.angle
    error = None if setpoint is None or angle is None else setpoint - angle
    values = [('active', 'true' if snapshot.active else 'false'),
              ('feedback age [s]', _number(snapshot.feedback_age)),
              ('set-point [deg]', _number(setpoint)),
              ('angle [deg]', _number(angle)),
              ('error [deg]', _number(error)),
              ('command', _number(snapshot.command))]
    if snapshot.idz_edges is not None:
        values += [('IDZ lower edge', _number(snapshot.idz_edges[0])),
                   ('IDZ upper edge', _number(snapshot.idz_edges[1]))]
    for name, (value, std) in snapshot.estimates.items():
        values += [(name, _number(value)), (f'{name} std', _number(std))]
    return HealthStatus(level, message, tuple(values))

"""
The machines a joint's data do not rule out, and a controller's check over them.

See methods 5.8.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
import math
from typing import Callable, Mapping, Sequence

from hydro_sdp.core.control.controller_spec import ControllerSpec
from hydro_sdp.core.control.loop_check import check_loop, CheckSettings, LoopCheck
from hydro_sdp.core.errors import HydroSdpError
from hydro_sdp.core.model.command_span import command_span
from hydro_sdp.core.model.effects import ValveLag
from hydro_sdp.core.model.joint_model import JointModel
from hydro_sdp.core.model.static_maps.pwl import PwlMap
from hydro_sdp.core.model.static_maps.registry import MAP_KINDS
from hydro_sdp.core.model.timing import SamplePeriod
from hydro_sdp.core.model.undetermined import EDGES
import numpy as np

#: Standard errors a map parameter is moved by, each way.
SPREAD = 2.0
#: Factors the valve lag's time constant is scaled by.
LAG_FACTORS = (0.5, 1.5)
#: Knots a side of a map whose dead-zone edge is moved (:func:`with_edge_at`).
_EDGE_KNOTS = 41


@dataclass(frozen=True)
class Plausible:
    """
    One model the data do not rule out.

    Attributes
    ----------
    name : str
        What was changed (``dead_zone[0] +2 SE``, ``delay -1 sample``, ``family pwl``...).

    """

    name: str
    model: JointModel


def _split_key(key: str) -> tuple[str, int | None]:
    """Split a model-file parameter name, ``name`` or ``name[i]``, into name and index."""
    name, _, index = key.partition('[')
    return name, int(index.rstrip(']')) if index else None


def _with_map_value(model: JointModel, key: str, value: float) -> JointModel | None:
    """Return ``model`` with map parameter ``key`` (``name`` or ``name[i]``) set, or None."""
    mapping = model.static_map.to_mapping()
    name, index = _split_key(key)
    if name not in mapping:
        return None
    if index is not None:
        values = mapping[name]
        if not isinstance(values, list):
            return None
        values = list(values)
        values[index] = value
        mapping[name] = values
    else:
        mapping[name] = value
    try:
        return replace(model, static_map=MAP_KINDS[model.kind].from_mapping(mapping))
    except (HydroSdpError, ValueError, TypeError):
        return None  # the change leaves the family's domain (edges crossing rest...)


def _map_value(model: JointModel, key: str) -> float | None:
    name, index = _split_key(key)
    value = model.static_map.to_mapping().get(name)
    if index is not None and isinstance(value, list):
        return float(value[index])
    return float(value) if isinstance(value, (int, float)) else None


def _map_edges(model: JointModel, limits: tuple[float, float]) -> tuple[float, float]:
    """Return the map's dead-zone edges, or for a map without one where its speed leaves 0."""
    if model.dead_zone is not None:
        return model.dead_zone
    rest = model.rest_command
    grid = np.linspace(limits[0], limits[1], 2001)
    speeds = np.abs(model.rate(grid))
    still = grid[speeds <= 1e-9 * max(float(speeds.max()), 1e-300)]
    below, above = still[still <= rest], still[still >= rest]
    return (float(below.min()) if below.size else rest, float(above.max()) if above.size else rest)


def with_edge_at(model: JointModel, side: int, edge: float) -> JointModel | None:
    """
    Return ``model`` with one dead-zone edge moved to ``edge``, as a piecewise-linear map.

    ``model``: the model; the commands its IDZ table covers (``command_span``: the input limits,
    else the map's own range) bound the stretch.
    ``side``: 0 for the negative edge, 1 for the positive one.
    ``edge``: the new edge, input units (clipped between rest and the limit).
    Returns: the changed model, or None where it has no command range to stretch over.
    """
    try:
        limits = command_span(model)
    except HydroSdpError:
        return None
    rest, limit = model.rest_command, limits[side]
    edges = _map_edges(model, limits)
    old = edges[side]
    new = min(max(edge, limits[0]), rest) if side == 0 else max(min(edge, limits[1]), rest)
    if abs(new - old) <= 1e-9 * max(1.0, abs(limit - rest)):
        return model
    moving = np.linspace(limit, new, _EDGE_KNOTS)
    scale = (old - limit) / (new - limit) if new != limit else 1.0
    moving_speeds = model.rate(limit + (moving - limit) * scale)
    other = np.append(np.linspace(rest, limits[1 - side], _EDGE_KNOTS), edges[1 - side])
    knots = np.concatenate([moving, [rest], other])
    speeds = np.concatenate([moving_speeds, [0.0], model.rate(other)])
    order = np.argsort(knots, kind='stable')
    knots, speeds = knots[order], speeds[order]
    keep = np.concatenate([[True], np.diff(knots) > 1e-9 * max(1.0, abs(limit - rest))])
    try:
        static_map = PwlMap(tuple(knots[keep]), tuple(np.maximum.accumulate(speeds[keep])))
        return replace(model, static_map=static_map)
    except HydroSdpError:
        return None


def _with_bounded_value(model: JointModel, key: str, value: float) -> JointModel | None:
    """Return ``model`` with an undetermined value set: a map key, else the edge moved."""
    changed = _with_map_value(model, key, value)
    if changed is None and key in EDGES:
        changed = with_edge_at(model, EDGES.index(key), value)
    return changed


def plausible_models(model: JointModel, *, standard_errors: Mapping[str, float],
                     dt: SamplePeriod,
                     families: Sequence[JointModel] = ()) -> tuple[Plausible, ...]:
    """
    Return the models one change away from ``model`` that its data do not rule out.

    ``standard_errors``: standard errors of its map parameters, by model-file name
    (``dead_zone[0]``).
    ``dt``: the records' sample period, s: the delay's resolution.
    ``families``: models of the other map families within the held-out tie band.
    Returns: in the order: families, map parameters, undetermined edges, delay, lag.
    """
    found = [Plausible(f'family {other.kind}', other) for other in families]
    bounded = {entry.parameter: entry for entry in model.undetermined}
    for key, error in sorted(standard_errors.items()):
        value = _map_value(model, key)
        if value is None or key in bounded or not (math.isfinite(error) and error > 0.0):
            continue
        for sign in (-1.0, 1.0):
            changed = _with_map_value(model, key, value + sign * SPREAD * error)
            if changed is not None:
                found.append(Plausible(f'{key} {sign * SPREAD:+g} SE', changed))
    for key, entry in sorted(bounded.items()):
        for end, label in zip(entry.bound, ('low', 'high')):
            if not math.isfinite(end):
                continue
            changed = _with_bounded_value(model, key, end)
            if changed is not None and changed.static_map != model.static_map:
                found.append(Plausible(f'{key} at the {label} end of its bound, {end:.4g}',
                                       changed))
    for sign in (-1, 1):
        delay = model.delay + sign * dt
        if delay >= 0.0:
            found.append(Plausible(f'delay {sign:+d} sample', replace(model, delay=delay)))
    lag = model.effect(ValveLag.name)
    if isinstance(lag, ValveLag):
        for factor in LAG_FACTORS:
            effects = tuple(replace(e, time_constant=e.time_constant * factor)
                            if isinstance(e, ValveLag) else e for e in model.effects)
            found.append(Plausible(f'valve_lag x{factor:g}', replace(model, effects=effects)))
    return tuple(found)


@dataclass(frozen=True, eq=False)
class PlausibleCheck:
    """A controller's closed-loop check on every plausible model."""

    checks: tuple[tuple[Plausible, LoopCheck], ...]

    @property
    def failed(self) -> tuple[tuple[Plausible, LoopCheck], ...]:
        """Return the models the controller fails on, with their checks."""
        return tuple(pair for pair in self.checks if not pair[1].passed)

    def worst(self) -> dict[str, tuple[float, str]]:
        """
        Return the worst figure of each metric and the model that gave it.

        Returns: ``settling_time`` (s), ``overshoot`` (%), ``steady_error`` (deg), ``pulse_rate``
        (per s of hold): ``(value, model name)``; empty without checks.
        """
        metrics: dict[str, Callable[[LoopCheck], float]] = {
            'settling_time': lambda c: max((m.settling_time for m in c.steps), default=0.0),
            'overshoot': lambda c: max((m.overshoot for m in c.steps), default=0.0),
            'steady_error': lambda c: max((abs(m.steady_error) for m in c.steps), default=0.0),
            'pulse_rate': lambda c: c.chatter.pulse_rate,
        }
        worst: dict[str, tuple[float, str]] = {}
        for metric, read in metrics.items():
            for plausible, check in self.checks:
                value = float(read(check))
                value = math.inf if math.isnan(value) else value
                if metric not in worst or value > worst[metric][0]:
                    worst[metric] = (value, plausible.name)
        return worst

    def to_mapping(self) -> dict[str, object]:
        """Return what the controller file records: the models tried and the worst figures."""
        return {
            'models': [p.name for p, _ in self.checks],
            'failed': [p.name for p, _ in self.failed],
            'worst': {metric: {'value': value if math.isfinite(value) else None, 'model': name}
                      for metric, (value, name) in self.worst().items()},
        }


def check_over(models: Sequence[Plausible], spec: ControllerSpec,
               stroke: tuple[float, float], settings: CheckSettings) -> PlausibleCheck:
    """Run the closed-loop check of ``spec`` on each of ``models``."""
    return PlausibleCheck(tuple((plausible, check_loop(plausible.model, spec, stroke,
                                                       settings=settings))
                                for plausible in models))

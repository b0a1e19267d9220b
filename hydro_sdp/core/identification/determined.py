"""
What the data determine of a map: which edges and parameters are bounds, not points.

The reasoning is in docs/methods.md section 13.9.

"""

from __future__ import annotations

import math
from typing import Sequence

from hydro_sdp.core.identification.delay import LevelSpeed
from hydro_sdp.core.identification.map_fit.sdp import moving_levels
from hydro_sdp.core.model.joint_model import JointModel
from hydro_sdp.core.model.undetermined import EDGES, Undetermined
import numpy as np


def undetermined_edges(points: Sequence[LevelSpeed], rest: float) -> tuple[Undetermined, ...]:
    """
    Return the dead-zone edges that no still command brackets, with their bounds.

    ``points``: speed of every command level held (or along the command, routine operation).
    Returns: one entry per edge the data leave between rest and the innermost moving command.
    """
    if not points:
        return ()
    levels = np.array([p.level for p in points])
    speeds = np.array([p.speed for p in points])
    # Moved at all: a level that creeps is no still level, however slow.
    go = np.abs(speeds) > 3.0 * np.array([p.standard_error for p in points])
    fastest = float(np.max(np.abs(speeds)))
    found = []
    for side, sign in ((0, -1.0), (1, 1.0)):
        away = sign * (levels - rest)
        moved = go & (away > 0.0) & (sign * speeds > 0.0)
        if not np.any(moved):
            continue
        inner = int(np.flatnonzero(moved)[np.argmin(away[moved])])
        if np.any(~go & (away > 0.0) & (away < away[inner])):
            continue        # a still command beyond rest brackets the edge
        level, speed = float(levels[inner]), abs(float(speeds[inner]))
        share = min(speed / fastest, 1.0) if fastest > 0.0 else 0.0
        first = rest + 0.25 * (level - rest)
        step = abs(level - rest) / 8.0
        found.append(Undetermined(
            f'dead_zone[{side}]', (min(rest, level), max(rest, level)),
            f'no command between rest {rest:.4g} and {level:.4g} was held, and at {level:.4g} '
            f'the joint moved at {speed:.3g} deg/s ({100.0 * share:.0f} % of its fastest)',
            f'hold commands from {first:.4g} to {level:.4g} (steps of about {step:.2g})',
            share))
    return tuple(found)


#: A parameter is pinned when two standard errors stay below this share of its size.
PINNED = 1.0


def unpinned(values: dict[str, float], errors: dict[str, float],
             levels_a_side: tuple[int, int]) -> tuple[Undetermined, ...]:
    """
    Return the parameters whose standard errors leave them unpinned, with their 2-SE bounds.

    ``values``: the map's parameters by model-file name (``curvature[0]``).
    ``errors``: their standard errors (a parameter without one is not judged).
    ``levels_a_side``: command levels that moved the joint below and above rest.
    Returns: one entry per parameter with ``2 SE > PINNED |value|`` (or no finite SE).
    """
    found = []
    for name, value in values.items():
        if name in EDGES or name not in errors:
            continue
        error = errors[name]
        if math.isfinite(error) and 2.0 * error <= PINNED * abs(value):
            continue
        side = name.endswith('[0]')
        levels = levels_a_side[0 if side else 1]
        spread = 2.0 * error if math.isfinite(error) else math.inf
        found.append(Undetermined(
            name, (value - spread, value + spread),
            f'its standard error {error:.3g} is as large as it is ({value:.4g}): '
            f'{levels} levels moved the joint on that side',
            'hold more command levels on that side, spread from the edge to the end of the '
            "valve's range"))
    return tuple(found)


def parameters(model: JointModel) -> list[tuple[str, float]]:
    """Return a model's map parameters by model-file name (``speeds[3]``), in file order."""
    mapping = model.static_map.to_mapping()
    out = []
    for key, value in mapping.items():
        if isinstance(value, list):
            out += [(f'{key}[{i}]', float(item)) for i, item in enumerate(value)]
        elif isinstance(value, (int, float)) and not isinstance(value, bool):
            out.append((key, float(value)))
    return out


def moving_levels_a_side(points: Sequence[LevelSpeed], rest: float) -> tuple[int, int]:
    """Return how many distinct levels moved the joint below and above rest."""
    if not points:
        return 0, 0
    levels = np.array([p.level for p in points])
    speeds = np.array([p.speed for p in points])
    go = moving_levels(speeds, np.array([p.standard_error for p in points]))
    return (len(set(levels[go & (levels < rest)].tolist())),
            len(set(levels[go & (levels > rest)].tolist())))

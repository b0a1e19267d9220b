"""
What the data determine of a map: dead-zone edges no held command brackets.

An edge lies between the outermost command that leaves the joint still and the innermost
that moves it. Where no command between rest and the innermost moving one was used, the
data bound the edge by those two and say nothing of where in between it is
(docs/methods.md section 13.9).

"""

from __future__ import annotations

from typing import Sequence

from hydro_sdp.core.identification.delay import LevelSpeed
from hydro_sdp.core.identification.map_fit.sdp import moving_levels
from hydro_sdp.core.model.static_maps import StaticMap
from hydro_sdp.core.model.undetermined import Undetermined
import numpy as np


def undetermined_edges(points: Sequence[LevelSpeed], static_map: StaticMap,
                       rest: float) -> tuple[Undetermined, ...]:
    """
    Return the dead-zone edges that no still command brackets, with their bounds.

    Parameters
    ----------
    points : sequence of LevelSpeed
        Speed of every command level held (or along the command, routine operation).
    static_map : StaticMap
        The identified map (its dead-zone is what is judged).
    rest : float
        Rest command.

    Returns
    -------
    tuple[Undetermined, ...]
        One entry per edge the data leave between rest and the innermost moving command.

    """
    if static_map.dead_zone is None or not points:
        return ()
    levels = np.array([p.level for p in points])
    speeds = np.array([p.speed for p in points])
    go = moving_levels(speeds, np.array([p.standard_error for p in points]))
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

"""Fitting the second paper's polynomial gain map (``poly``) to per-level speeds."""

from __future__ import annotations

from typing import Sequence

from hydro_sdp.core.delay import LevelSpeed
from hydro_sdp.core.errors import DataError
from hydro_sdp.core.map_fit.data import MapFit
from hydro_sdp.core.static_maps import PolyMap
import numpy as np


def fit_poly(points: Sequence[LevelSpeed], rest: float, *, degree: int = 3) -> MapFit[PolyMap]:
    """
    Fit the second paper's polynomial gain ``b(v)`` to per-level speeds, per direction.

    Parameters
    ----------
    points : sequence of LevelSpeed
        Per-level speeds.
    rest : float
        Rest command; must be 0 (the polynomial gain divides by the command).
    degree : int
        Highest polynomial degree (lowered when a side has few points).

    Returns
    -------
    MapFit
        The fitted ``poly`` map.

    """
    if rest != 0.0:
        raise DataError('the polynomial gain map needs commands that rest at 0')
    levels = np.array([p.level for p in points])
    speeds = np.array([p.speed for p in points])
    errors = np.array([p.standard_error for p in points])
    coefficients = []
    residual = 0.0
    for side in (levels < 0.0, levels > 0.0):
        count = int(np.sum(side))
        if count < 2:
            raise DataError('the polynomial gain map needs at least two levels on each side')
        order = int(min(degree, count - 2)) if count > 2 else 0
        gain = speeds[side] / levels[side]
        weights = np.abs(levels[side]) / np.maximum(errors[side], 1e-9)
        fit = np.polynomial.polynomial.polyfit(levels[side], gain, order, w=weights)
        coefficients.append(tuple(fit.tolist()))
        predicted = levels[side] * np.polynomial.polynomial.polyval(levels[side], fit)
        residual += float(np.sum((predicted - speeds[side]) ** 2))
    static_map = PolyMap(gain_negative=coefficients[0], gain_positive=coefficients[1],
                         command_range=(float(levels.min()), float(levels.max())))
    return MapFit(static_map, 'points', 0.0, 0.5 * residual)

"""Fitting the saturating power-law map (``power_sat``) to experiments (methods 2.7)."""

from __future__ import annotations

import functools
from typing import Sequence

from hydro_sdp.core.arrays import FloatArray
from hydro_sdp.core.identification.delay import LevelSpeed
from hydro_sdp.core.identification.map_fit.columns import BatchedResiduals
from hydro_sdp.core.identification.map_fit.data import (
    covariance_errors, FitData, FitMethod, MapFit, RateFunction, TR_SOLVER)
from hydro_sdp.core.model.static_maps import power_sat_rate, PowerSatMap, SdpMap
import numpy as np
from scipy.optimize import least_squares

NAMES = ('saturation_velocity[0]', 'curvature[0]', 'exponent[0]', 'dead_zone[0]',
         'saturation_velocity[1]', 'curvature[1]', 'exponent[1]', 'dead_zone[1]')
#: Exponents tried as starts.
START_EXPONENTS = (1.0, 2.0, 3.0, 5.0)
#: Standard errors by which a level's mean speed must exceed zero to count as moving.
MOVING_T = 5.0


def power_sat_rate_function(x: FloatArray) -> RateFunction:
    """Return the map of ``x = (vn, cn, nn, a3, vp, cp, np, a6)`` (rates in deg/s)."""
    return lambda v: power_sat_rate(v, *(float(value) for value in x[:8]))


def power_sat_from_vector(x: FloatArray) -> PowerSatMap:
    """Build a :class:`PowerSatMap` from ``(vn, cn, nn, a3, vp, cp, np, a6)``."""
    return PowerSatMap(dead_zone=(float(x[3]), float(x[7])),
                       saturation_velocity=(float(x[0]), float(x[4])),
                       curvature=(float(x[1]), float(x[5])), exponent=(float(x[2]), float(x[6])))


def _bounds(levels: FloatArray, speeds: FloatArray, errors: FloatArray, rest: float
            ) -> tuple[FloatArray, FloatArray]:
    """Bounds of ``(vn, cn, nn, a3, vp, cp, np, a6)`` from the per-level speeds."""
    scale = max(float(np.max(np.abs(levels - rest))), 1e-9)
    peak = max(float(np.max(np.abs(speeds))), 1e-9)
    lower, upper = [], []
    for sign in (-1.0, 1.0):
        side = sign * (levels - rest) > 0.0
        fastest = max(float(np.max(sign * speeds[side], initial=0.0)), 1e-3 * peak)
        # A level moves the joint when its mean speed, in the commanded direction, stands
        # clear of its own noise: a convex valve just outside its edge creeps at well under
        # a percent of its full speed, and an edge put beyond such a level predicts a joint
        # standing still where it crept all along.
        moving = side & (sign * speeds > MOVING_T * errors)
        # The edge lies between rest and the innermost level that moves the joint.
        inner = float(np.min(sign * (levels[moving] - rest), initial=scale))
        edge = (rest - inner, rest) if sign < 0 else (rest, rest + inner)
        if sign < 0:
            lower += [-1.5 * fastest, 1e-3 / scale, 0.5, edge[0]]
            upper += [-0.7 * fastest, 1e3 / scale, 8.0, edge[1]]
        else:
            lower += [0.7 * fastest, 1e-3 / scale, 0.5, edge[0]]
            upper += [1.5 * fastest, 1e3 / scale, 8.0, edge[1]]
    return np.array(lower), np.array(upper)


def power_sat_start(points: Sequence[LevelSpeed], rest: float, start: SdpMap
                    ) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Return the starting parameters and their bounds from the per-level speeds."""
    # Keyed by the bits of the numbers: -0.0 is not 0.0, and a NaN is itself.
    table = np.array([[p.level, p.speed, p.standard_error] for p in points], dtype=np.float64)
    given = np.array([rest, start.dead_zone[0], start.dead_zone[1]], dtype=np.float64)
    x0, lower, upper = _start(table.tobytes(), given.tobytes())
    return np.array(x0), np.array(lower), np.array(upper)


@functools.lru_cache(maxsize=8)
def _start(table: bytes, given: bytes) -> tuple[tuple[float, ...], ...]:
    """Return :func:`power_sat_start` of the points' and the edges' bits, as tuples."""
    points = np.frombuffer(table).reshape(-1, 3)
    levels, speeds = points[:, 0].copy(), points[:, 1].copy()
    weights = 1.0 / np.maximum(points[:, 2], 1e-3 * np.max(np.abs(speeds)))
    rest, low, high = np.frombuffer(given).tolist()
    lower, upper = _bounds(levels, speeds, points[:, 2], rest)
    best: tuple[float, FloatArray] | None = None
    for exponent in START_EXPONENTS:
        x0 = np.array([lower[0], 0.0, exponent, low, upper[4], 0.0, exponent, high])
        reach = [max(low - float(np.min(levels)), 1e-6), max(float(np.max(levels)) - high, 1e-6)]
        x0[[1, 5]] = 1.0 / np.array(reach)
        x0 = np.clip(x0, lower + 1e-9 * np.abs(lower), upper - 1e-9 * np.abs(upper))
        result = least_squares(lambda x: (power_sat_rate_function(x)(levels) - speeds) * weights,
                               x0, bounds=(lower, upper), x_scale='jac')
        if best is None or result.cost < best[0]:
            best = (float(result.cost), np.asarray(result.x))
    assert best is not None
    return tuple(best[1].tolist()), tuple(lower.tolist()), tuple(upper.tolist())


def fit_power_sat(data: FitData, points: Sequence[LevelSpeed], rest: float, start: SdpMap, *,
                  method: FitMethod = 'rr') -> MapFit[PowerSatMap]:
    """
    Fit the saturating power-law map by regret-regression or output error.

    ``start``: an ``sdp`` fit: its edges and saturation speeds start the search.
    ``method``: ``rr`` (``beta`` estimated) or ``oe`` (``beta = 0``, the simulation error).
    """
    x0, lower, upper = power_sat_start(points, rest, start)
    if method == 'rr':
        residuals = BatchedResiduals(
            data, lambda x: (power_sat_rate_function(x), float(x[8])))
        result = least_squares(residuals, np.r_[x0, 0.5],
                               bounds=(np.r_[lower, 0.0], np.r_[upper, 1.0]), x_scale='jac',
                               tr_solver=TR_SOLVER, **residuals.options)
        beta = float(result.x[8])
    else:
        residuals = BatchedResiduals(data, lambda x: (power_sat_rate_function(x), 0.0))
        result = least_squares(residuals, x0, bounds=(lower, upper), x_scale='jac',
                               tr_solver=TR_SOLVER, **residuals.options)
        beta = 0.0
    x = np.asarray(result.x)
    errors = covariance_errors(np.asarray(result.jac), float(result.cost), data.samples)
    names = NAMES + (('beta',) if method == 'rr' else ())
    return MapFit(power_sat_from_vector(x), method, beta, float(result.cost),
                  dict(zip(names, errors.tolist())), int(result.nfev), len(START_EXPONENTS))

"""Fitting eq. (5) of West et al. (2018), the ``sdp`` map, to experiments (methods 2.1-2.5)."""

from __future__ import annotations

import math
from typing import Sequence

from hydro_sdp.core.arrays import FloatArray
from hydro_sdp.core.errors import DataError
from hydro_sdp.core.identification.delay import LevelSpeed
from hydro_sdp.core.identification.map_fit.columns import BatchedResiduals, forward_jacobian
from hydro_sdp.core.identification.map_fit.data import (
    covariance_errors, FIT_METHODS, FitData, FitMethod, MapFit, RateFunction)
from hydro_sdp.core.model.static_maps import sdp_rate, SdpMap
import numpy as np
import numpy.typing as npt
from scipy.optimize import least_squares, minimize, OptimizeResult

SDP_NAMES = ('saturation_velocity[0]', 'curvature[0]', 'dead_zone[0]',
             'saturation_velocity[1]', 'curvature[1]', 'dead_zone[1]')


def sdp_rate_function(x: FloatArray) -> RateFunction:
    """Return the eq. (5) map for ``x = (vn, cn, a3, vp, cp, a6)`` (rates in deg/s)."""
    v_neg, c_neg, low, v_pos, c_pos, high = (float(value) for value in x[:6])

    def rate(v: FloatArray) -> FloatArray:
        return sdp_rate(v, v_neg, c_neg, low, v_pos, c_pos, high)
    return rate


def sdp_from_rate_vector(x: FloatArray) -> SdpMap:
    """Build an :class:`SdpMap` from ``(vn, cn, a3, vp, cp, a6)`` (rates in deg/s)."""
    return SdpMap(dead_zone=(float(x[2]), float(x[5])),
                  saturation_velocity=(float(x[0]), float(x[3])),
                  curvature=(float(x[1]), float(x[4])))


def initial_sdp(points: Sequence[LevelSpeed], rest: float) -> FloatArray:
    """
    Return starting values of ``(vn, cn, a3, vp, cp, a6)`` from per-level speeds.

    ``points``: mean speeds per command level.
    """
    check_excitation(points, rest)
    levels = np.array([p.level for p in points])
    speeds = np.array([p.speed for p in points])
    errors = np.array([p.standard_error for p in points])
    peak = np.max(np.abs(speeds))
    moving = moving_levels(speeds, errors)
    scale = max(float(np.max(np.abs(levels - rest))), 1e-9)
    guess = []
    for sign in (-1.0, 1.0):
        side = sign * (levels - rest) > 0
        go = side & moving & (sign * speeds > 0)
        still = side & ~moving
        inner_moving = float(np.min(sign * (levels[go] - rest)))
        outer_still = float(np.max(sign * (levels[still] - rest), initial=0.0))
        outer_still = outer_still if outer_still < inner_moving else 0.0
        edge = rest + sign * 0.5 * (outer_still + inner_moving)
        fastest = sign * np.max(sign * speeds[go])
        guess.append((1.2 * fastest, 3.0 / scale, edge))
    x0 = np.array([guess[0][0], guess[0][1], guess[0][2], guess[1][0], guess[1][1],
                   guess[1][2]])
    weights = 1.0 / np.maximum(errors, 1e-3 * peak)
    lower, upper = sdp_bounds(levels, speeds, rest)
    x0 = np.clip(x0, lower[:6], upper[:6])
    result = least_squares(lambda x: (sdp_rate_function(x)(levels) - speeds) * weights, x0,
                           bounds=(lower[:6], upper[:6]), x_scale='jac')
    return np.asarray(result.x)


def sdp_bounds(levels: FloatArray, speeds: FloatArray, rest: float
               ) -> tuple[FloatArray, FloatArray]:
    """Return bounds of ``(vn, cn, a3, vp, cp, a6, beta)`` from the range of the data."""
    scale = max(np.max(np.abs(levels - rest)), 1e-9)
    peak = max(np.max(np.abs(speeds)), 1e-9)
    low_v, high_v = float(np.min(levels)), float(np.max(levels))
    lower = np.array([-20.0 * peak, 1e-3 / scale, min(low_v, rest) - 1e-9, 1e-9,
                      1e-3 / scale, rest, 0.0])
    upper = np.array([-1e-9, 1e3 / scale, rest, 20.0 * peak, 1e3 / scale,
                      max(high_v, rest) + 1e-9, 1.0])
    return lower, upper


def check_excitation(points: Sequence[LevelSpeed], rest: float) -> None:
    """
    Refuse data that cannot identify a two-sided map.

    ``points``: mean speeds per command level.
    Raises DataError if the joint never moves, or moves in one direction only.
    """
    if not points:
        raise DataError('no excitation: no command level was held long enough to measure a '
                        'speed')
    speeds = np.array([p.speed for p in points])
    errors = np.array([p.standard_error for p in points])
    levels = np.array([p.level for p in points])
    moving = moving_levels(speeds, errors)
    if not np.any(moving & (np.abs(speeds) > 0.05 * np.max(np.abs(speeds)))):
        raise DataError('no excitation: the joint never moves (are all commands inside the '
                        'dead-zone?)')
    up = np.any(moving & (speeds > 0) & (levels > rest))
    down = np.any(moving & (speeds < 0) & (levels < rest))
    if not (up and down):
        direction, sign = ('positive', -1.0) if up else ('negative', 1.0)
        beyond = 'below' if sign < 0 else 'above'
        side = sign * (levels - rest) > 0
        if not np.any(side):
            seen = f'no command {beyond} rest {rest:g} was held'
        else:
            reach = rest + sign * float(np.max(sign * (levels[side] - rest)))
            seen = (f'the levels held {beyond} rest reach only {reach:.4g} and leave it still; '
                    f'commands {beyond} {reach:.4g} were never held')
        raise DataError(f'the joint moves in the {direction} direction only: {seen}; the map '
                        'needs commands on both sides of rest that move it')


def moving_levels(speeds: FloatArray, errors: FloatArray) -> npt.NDArray[np.bool_]:
    """Tell which levels move the joint: 3 standard errors from zero and 2 % of the fastest."""
    # One test of "this level moves the joint" for the checks and the starting values, so
    # data the checks accept always give the starting values something on both sides.
    peak = max(float(np.max(np.abs(speeds))), 1e-9)
    return (np.abs(speeds) > np.maximum(3.0 * errors, 1e-9)) & (np.abs(speeds) > 0.02 * peak)


def _to_free(x: FloatArray, rest: float, scale: float) -> FloatArray:
    """Map ``(vn, cn, a3, vp, cp, a6, beta)`` to unconstrained values (logs and a logit)."""
    tiny = 1e-9 * scale
    beta = min(max(x[6], 1e-6), 1.0 - 1e-6)
    return np.array([math.log(max(-x[0], 1e-12)), math.log(x[1]), math.log(max(rest - x[2], tiny)),
                     math.log(max(x[3], 1e-12)), math.log(x[4]), math.log(max(x[5] - rest, tiny)),
                     math.log(beta / (1.0 - beta))])


def _to_natural(p: FloatArray, rest: float) -> FloatArray:
    """Invert :func:`_to_free`: signs, ordering ``a3 <= rest <= a6`` and ``0 < beta < 1`` hold."""
    # A wild Levenberg-Marquardt step must not overflow; such points just cost a lot.
    p = np.clip(p, -50.0, 50.0)
    return np.array([-math.exp(p[0]), math.exp(p[1]), rest - math.exp(p[2]), math.exp(p[3]),
                     math.exp(p[4]), rest + math.exp(p[5]), 1.0 / (1.0 + math.exp(-p[6]))])


def _natural_derivative(p: FloatArray) -> FloatArray:
    """Return the derivative of each natural parameter with respect to its free value."""
    p = np.clip(p, -50.0, 50.0)
    beta = 1.0 / (1.0 + math.exp(-p[6]))
    return np.array([-math.exp(p[0]), math.exp(p[1]), -math.exp(p[2]), math.exp(p[3]),
                     math.exp(p[4]), math.exp(p[5]), beta * (1.0 - beta)])


def fit_sdp(data: FitData, points: Sequence[LevelSpeed], rest: float, *,
            method: FitMethod = 'rr', starts: int = 4,
            polish: FitData | None = None) -> MapFit[SdpMap]:
    """
    Fit eq. (5) of West et al. by regret-regression or by output error.

    ``method``: ``rr`` (least squares on the regret-regression residuals, ``beta`` estimated) or
    ``oe`` (Nelder-Mead on the mean simulation error).
    ``starts``: number of starting points (the curvatures are varied around the start).
    ``polish``: larger data set: the starts run on ``data`` (a sample of it) and the best is
    refined on ``polish``.
    Returns: the fitted ``sdp`` map with standard errors.
    """
    if method not in FIT_METHODS:
        raise DataError(f"method must be 'rr' or 'oe', got {method!r}")
    base = initial_sdp(points, rest)
    levels = np.array([p.level for p in points])
    lower, upper = sdp_bounds(levels, np.array([p.speed for p in points]), rest)
    scale = max(float(np.max(np.abs(levels - rest))), 1e-9)
    factors = [1.0, 0.5, 2.0, 4.0, 0.25][:max(starts, 1)]

    def natural_map(p: FloatArray) -> tuple[RateFunction, float]:
        x = _to_natural(p, rest)
        return sdp_rate_function(x), x[6]

    def rr_fit(fit_data: FitData, free: FloatArray) -> OptimizeResult:
        residuals = BatchedResiduals(fit_data, natural_map)
        return least_squares(residuals, free, method='lm', x_scale=1.0,
                             **residuals.options)

    def oe_fit(fit_data: FitData, x0: FloatArray, iterations: int) -> OptimizeResult:
        return minimize(lambda x: fit_data.mean_experiment_sse(sdp_rate_function(x)), x0,
                        method='Nelder-Mead', bounds=list(zip(lower[:6], upper[:6])),
                        options={'maxiter': iterations, 'maxfev': iterations, 'xatol': 1e-7,
                                 'fatol': 1e-12, 'adaptive': True})

    best: tuple[float, OptimizeResult] | None = None
    evaluations = 0
    for factor in factors:
        x0 = base.copy()
        x0[[1, 4]] *= factor
        if method == 'rr':
            result = rr_fit(data, _to_free(np.r_[x0, 0.5], rest, scale))
            cost = float(result.cost)
        else:
            result = oe_fit(data, np.clip(x0, lower[:6], upper[:6]), 6000)
            cost = 0.5 * float(np.sum(data.residuals(sdp_rate_function(result.x)) ** 2))
        evaluations += result.nfev
        if best is None or cost < best[0]:
            best = (cost, result)
    assert best is not None     # factors is never empty
    cost, result = best
    if polish is not None:
        data = polish
        result = rr_fit(data, result.x) if method == 'rr' else oe_fit(data, result.x, 2000)
        evaluations += result.nfev
    if method == 'rr':
        x = _to_natural(result.x, rest)
        cost = float(result.cost)
        # A parameter driven to its bound (beta at 0 or 1: the logit's slope underflows)
        # has no error; the others' errors are those with it held there.
        derivative = _natural_derivative(result.x)
        free = np.abs(derivative) > 1e-12
        errors = np.full(derivative.size, np.inf)
        errors[free] = covariance_errors(np.asarray(result.jac)[:, free] / derivative[free],
                                         cost, data.samples)
    else:
        x = np.r_[result.x, 0.0]
        cost = 0.5 * float(np.sum(data.residuals(sdp_rate_function(x)) ** 2))
        jacobian = forward_jacobian(data, lambda p: (sdp_rate_function(p), 0.0), x[:6])
        errors = covariance_errors(jacobian, cost, data.samples)
    names = SDP_NAMES + (('beta',) if method == 'rr' else ())
    return MapFit(sdp_from_rate_vector(x), method, float(x[6]), cost,
                  dict(zip(names, errors.tolist())), evaluations, len(factors))

"""The map families fitted to the one-step increments of routine operation (methods 15.5)."""

from __future__ import annotations

from typing import Callable, Sequence

from hydro_sdp.core.arrays import FloatArray
from hydro_sdp.core.identification.delay import LevelSpeed
from hydro_sdp.core.identification.family_choice import FittedKind
from hydro_sdp.core.identification.map_fit import (
    fit_poly, initial_pwl, initial_sdp, MapFit, pwl_layout, RateFunction, sdp_bounds,
    sdp_from_rate_vector, SDP_NAMES, sdp_rate_function)
from hydro_sdp.core.identification.map_fit.data import covariance_errors
from hydro_sdp.core.identification.map_fit.power_sat import (
    NAMES as POWER_SAT_NAMES, power_sat_from_vector, power_sat_rate_function, power_sat_start)
from hydro_sdp.core.identification.routine.increments import Increments
from hydro_sdp.core.model.static_maps import PolyMap, PwlMap, SdpMap, StaticMap
from hydro_sdp.core.model.timing import SamplePeriod
import numpy as np
from scipy.optimize import least_squares


class _Residuals:
    """``dy_k - dt rate(v_{k-tau})`` summed per distinct command."""

    def __init__(self, data: Increments, dt: SamplePeriod) -> None:
        self.levels, inverse, counts = np.unique(data.command, return_inverse=True,
                                                 return_counts=True)
        self.means = np.bincount(inverse, weights=data.increment) / counts
        self.weights = np.sqrt(counts.astype(np.float64))
        self.within = float(np.sum((data.increment - self.means[inverse]) ** 2))
        self.samples = data.samples
        self.dt = dt

    def __call__(self, rate: RateFunction) -> FloatArray:
        return self.weights * (self.means - self.dt * rate(self.levels))


def _fit(residuals: _Residuals, rate_of: Callable[[FloatArray], RateFunction], x0: FloatArray,
         lower: FloatArray | None = None, upper: FloatArray | None = None
         ) -> tuple[FloatArray, float, FloatArray, int]:
    """Least squares over the increments; return the parameters, cost, errors, evaluations."""
    bounds = (-np.inf, np.inf) if lower is None or upper is None else (lower, upper)
    if lower is not None and upper is not None:
        x0 = np.clip(x0, lower, upper)
    result = least_squares(lambda x: residuals(rate_of(x)), x0, bounds=bounds, x_scale='jac')
    cost = float(result.cost) + 0.5 * residuals.within
    errors = covariance_errors(np.asarray(result.jac), cost, residuals.samples)
    return np.asarray(result.x), cost, errors, int(result.nfev)


def fit_sdp_increments(data: Increments, dt: SamplePeriod, points: Sequence[LevelSpeed],
                       rest: float) -> MapFit[SdpMap]:
    """
    Fit eq. (5) of West et al. (the ``sdp`` map) to the increments.

    ``dt``: sample period, s.
    ``points``: speeds along the command (the starting values and the bounds).
    Returns: the fit (``method`` ``increments``, ``beta`` 1) with standard errors.
    """
    residuals = _Residuals(data, dt)
    levels = np.array([p.level for p in points])
    lower, upper = sdp_bounds(levels, np.array([p.speed for p in points]), rest)
    x, cost, errors, count = _fit(residuals, sdp_rate_function, initial_sdp(points, rest),
                                  lower[:6], upper[:6])
    return MapFit(sdp_from_rate_vector(x), 'increments', 1.0, cost,
                  dict(zip(SDP_NAMES, errors.tolist())), count)


def fit_increments(kind: FittedKind, data: Increments, dt: SamplePeriod,
                   points: Sequence[LevelSpeed], rest: float, start: SdpMap) -> MapFit[StaticMap]:
    """
    Fit one map family to the increments.

    ``dt``: sample period, s.
    """
    if kind == 'sdp':
        return fit_sdp_increments(data, dt, points, rest)
    residuals = _Residuals(data, dt)
    if kind == 'power_sat':
        x0, lower, upper = power_sat_start(points, rest, start)
        x, cost, errors, count = _fit(residuals, power_sat_rate_function, x0, lower, upper)
        return MapFit(power_sat_from_vector(x), 'increments', 1.0, cost,
                      dict(zip(POWER_SAT_NAMES, errors.tolist())), count)
    if kind == 'pwl':
        layout = pwl_layout(residuals.levels, start.dead_zone)
        x0 = initial_pwl(layout, points)[:-1]

        def pwl_rate(x: FloatArray) -> RateFunction:
            speeds_at = layout.speeds(x)
            return lambda v: np.interp(v, layout.knots, speeds_at)
        x, cost, _, count = _fit(residuals, pwl_rate, x0, np.zeros(x0.size),
                                 np.full(x0.size, np.inf))
        return MapFit(PwlMap(knots=tuple(layout.knots.tolist()),
                             speeds=tuple(layout.speeds(x).tolist())),
                      'increments', 1.0, cost, {}, count)
    first = fit_poly(points, rest).static_map
    sizes = (len(first.gain_negative), len(first.gain_positive))

    def build(x: FloatArray) -> PolyMap:
        return PolyMap(tuple(x[:sizes[0]]), tuple(x[sizes[0]:]), first.command_range, rest)
    x, cost, _, count = _fit(residuals, lambda x: build(x).rate,
                             np.r_[first.gain_negative, first.gain_positive])
    return MapFit(build(x), 'increments', 1.0, cost, {}, count)

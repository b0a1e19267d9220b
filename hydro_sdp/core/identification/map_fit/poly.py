"""Fitting the second paper's polynomial gain map (``poly``) (methods 2.7)."""

from __future__ import annotations

from typing import Sequence
import warnings

from hydro_sdp.core.errors import DataError
from hydro_sdp.core.identification.delay import LevelSpeed
from hydro_sdp.core.identification.map_fit.columns import BatchedResiduals
from hydro_sdp.core.identification.map_fit.data import FitData, FitMethod, MapFit, TR_SOLVER
from hydro_sdp.core.model.static_maps import PolyMap
import numpy as np
from scipy.optimize import least_squares


def fit_poly(points: Sequence[LevelSpeed], rest: float, *, degree: int = 3,
             data: FitData | None = None, method: FitMethod = 'rr') -> MapFit[PolyMap]:
    """
    Fit the second paper's polynomial gain ``b(u)``, ``u = v - rest``, per direction.

    ``rest``: rest command (the gain divides by the command's distance from it).
    ``degree``: highest polynomial degree (lowered when a side has few points).
    ``data``: experiments to refine the coefficients on (default: the points' fit).
    """
    levels = np.array([p.level for p in points]) - rest
    speeds = np.array([p.speed for p in points])
    errors = np.array([p.standard_error for p in points])
    coefficients = []
    residual = 0.0
    for side in (levels < 0.0, levels > 0.0):
        count = np.unique(levels[side]).size     # a level held in several runs counts once
        if count < 2:
            raise DataError('the polynomial gain map needs at least two levels on each side')
        order = int(min(degree, count - 1))
        gain = speeds[side] / levels[side]
        weights = np.abs(levels[side]) / np.maximum(errors[side], 1e-9)
        # Fitted on the commands scaled to [-1, 1] (40-100 % cubed is ill-conditioned
        # otherwise), then expressed in the map's own coefficients. Levels a hair apart
        # still leave it ill-posed: the held-out family choice judges the result, and
        # numpy's warning would only reach the user as noise.
        with warnings.catch_warnings():
            warnings.simplefilter('ignore', np.exceptions.RankWarning)
            scaled = np.polynomial.Polynomial.fit(levels[side], gain, order, w=weights)
        fit = np.pad(scaled.convert().coef, (0, order + 1))[:order + 1]
        coefficients.append(tuple(fit.tolist()))
        predicted = levels[side] * np.polynomial.polynomial.polyval(levels[side], fit)
        residual += float(np.sum((predicted - speeds[side]) ** 2))
    command_range = (float(levels.min()) + rest, float(levels.max()) + rest)
    static_map = PolyMap(gain_negative=coefficients[0], gain_positive=coefficients[1],
                         command_range=command_range, rest=rest)
    if data is None:
        return MapFit(static_map, 'points', 0.0, 0.5 * residual)
    sizes = [len(c) for c in coefficients]

    def build(x: np.ndarray) -> PolyMap:
        return PolyMap(tuple(x[:sizes[0]]), tuple(x[sizes[0]:sizes[0] + sizes[1]]),
                       command_range, rest)

    start = np.r_[coefficients[0], coefficients[1]]
    if method == 'rr':
        residuals = BatchedResiduals(data, lambda x: (build(x).rate, float(x[-1])))
        result = least_squares(residuals, np.r_[start, 0.5], bounds=(
                                   np.r_[np.full(start.size, -np.inf), 0.0],
                                   np.r_[np.full(start.size, np.inf), 1.0]), x_scale='jac',
                               tr_solver=TR_SOLVER, **residuals.options)
        beta = float(result.x[-1])
    else:
        residuals = BatchedResiduals(data, lambda x: (build(x).rate, 0.0))
        result = least_squares(residuals, start, method='lm', **residuals.options)
        beta = 0.0
    return MapFit(build(result.x), method, beta, float(result.cost), {}, int(result.nfev))

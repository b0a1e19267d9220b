"""Fitting the monotone piecewise-linear map (``pwl``) to experiments (methods 2.7)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

from hydro_sdp.core.arrays import FloatArray
from hydro_sdp.core.identification.delay import LevelSpeed
from hydro_sdp.core.identification.map_fit.columns import BatchedResiduals
from hydro_sdp.core.identification.map_fit.data import (
    covariance_errors, FitData, FitMethod, MapFit, RateFunction, TR_SOLVER)
from hydro_sdp.core.model.static_maps import PwlMap
import numpy as np
from scipy.optimize import least_squares

#: Most knots beyond each edge at measured levels, and the quantile knots beyond it.
MAX_KNOTS = 12
QUANTILE_KNOTS = 12


@dataclass(frozen=True, eq=False)
class PwlLayout:
    """
    Knots of a ``pwl`` map and how its free parameters become speeds.

    Attributes
    ----------
    knots : FloatArray
        Commands, increasing: ``negative`` knots below the plateau, its one or two edges, then
        ``positive`` knots above it; input units.

    """

    knots: FloatArray
    negative: int
    positive: int

    def speeds(self, x: FloatArray) -> FloatArray:
        """Speed at each knot, deg/s, from the increments ``x`` (``beta`` may follow them)."""
        n_neg, n_pos = self.negative, self.positive
        negative = -np.cumsum(x[:n_neg][::-1])[::-1]       # outward from the lower edge
        positive = np.cumsum(x[n_neg:n_neg + n_pos])
        zeros = np.zeros(self.knots.size - n_neg - n_pos)
        return np.r_[negative, zeros, positive]


def pwl_layout(levels: FloatArray, dead_zone: tuple[float, float], *,
               knots_per_side: int | None = None) -> PwlLayout:
    """
    Place the knots: the plateau's edges and the commands beyond each.

    ``levels``: the distinct commands of the data, input units.
    ``dead_zone``: edges of the zero-speed plateau.
    ``knots_per_side``: knots beyond each edge, at quantiles of the commands there; default: one at
    every distinct command, or :data:`QUANTILE_KNOTS` quantiles when there are more than
    :data:`MAX_KNOTS`.
    """
    low, high = dead_zone
    # A side without data gets one knot past its edge: 1 input unit, or more where
    # the edge is so large (a plateau beyond every level) that 1 would round away.
    beyond = [max(1.0, 1e-9 * abs(edge)) for edge in (low, high)]
    sides = []
    for side, edge in ((levels[levels < low], low - beyond[0]),
                       (levels[levels > high], high + beyond[1])):
        side = np.unique(side)
        if side.size == 0:
            sides.append(np.array([edge]))
        elif knots_per_side is None and side.size <= MAX_KNOTS:
            sides.append(side)
        else:
            count = knots_per_side if knots_per_side is not None else QUANTILE_KNOTS
            sides.append(np.unique(np.quantile(side, np.linspace(0, 1, count))))
    knots_neg, knots_pos = sides
    knots = np.r_[knots_neg, low, high, knots_pos]
    if high <= low:
        knots = np.r_[knots_neg, low, knots_pos]
    return PwlLayout(knots, knots_neg.size, knots_pos.size)


def initial_pwl(layout: PwlLayout, points: Sequence[LevelSpeed]) -> FloatArray:
    """
    Return starting increments and ``beta`` whose speeds follow the per-level speeds.

    ``points``: mean speeds per command level.
    Returns: increments (:meth:`PwlLayout.speeds`), at least 1e-6 deg/s each, then ``beta`` 0.5.
    """
    n_neg, n_pos = layout.negative, layout.positive
    target = np.interp(layout.knots, [p.level for p in points], [p.speed for p in points])
    # Speeds rise towards the plateau on the negative side: each increment is the rise
    # from one knot to the next (the last to the edge's 0).
    return np.r_[np.maximum(np.diff(np.r_[target[:n_neg], 0.0]), 1e-6),
                 np.maximum(np.diff(np.r_[0.0, target[-n_pos:]]), 1e-6), 0.5]


def fit_pwl(data: FitData, points: Sequence[LevelSpeed], rest: float,
            dead_zone: tuple[float, float], *, knots_per_side: int | None = None,
            method: FitMethod = 'rr') -> MapFit[PwlMap]:
    """
    Fit a monotone piecewise-linear map by regret-regression or output error.

    ``method``: ``rr`` (``beta`` estimated) or ``oe`` (``beta = 0``: the simulation error).
    """
    layout = pwl_layout(data.levels, dead_zone, knots_per_side=knots_per_side)
    knots = layout.knots
    x0 = initial_pwl(layout, points)
    parameters = layout.negative + layout.positive
    # Output error is regret-regression with beta held at 0.
    top = 1.0 if method == 'rr' else 0.0
    lower = np.r_[np.zeros(parameters), 0.0]
    upper = np.r_[np.full(parameters, np.inf), max(top, 1e-12)]
    x0[-1] = min(x0[-1], top)

    def parametrised(x: FloatArray) -> tuple[RateFunction, float]:
        return (lambda v: np.interp(v, knots, layout.speeds(x))), \
            x[-1] if method == 'rr' else 0.0
    residuals = BatchedResiduals(data, parametrised)
    result = least_squares(residuals, np.clip(x0, lower, upper), bounds=(lower, upper),
                           x_scale='jac', tr_solver=TR_SOLVER,
                           **residuals.options)
    speeds = layout.speeds(result.x)
    static_map = PwlMap(knots=tuple(knots.tolist()), speeds=tuple(speeds.tolist()))
    errors = covariance_errors(result.jac, result.cost, data.samples)
    beta = float(result.x[-1]) if method == 'rr' else 0.0
    return MapFit(static_map, method, beta, float(result.cost),
                  {'beta': float(errors[-1])} if method == 'rr' else {}, int(result.nfev))

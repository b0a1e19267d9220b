"""
Fitting the static map of a joint to experiments (docs/methods.md section 2).

Every experiment predicts its angles from its initial state with
``pred_k = x_{k-1} + dt rate(v_{k-tau})``, ``Z_k = y_k - pred_k`` and
``x_k = pred_k + beta Z_k``: regret-regression (``rr``, the default) estimates
``beta`` with the map and so sits between the simulation (output-error) fit
(``beta = 0``) and the one-step equation-error fit (``beta = 1``), with
``beta`` near the Kalman gain of the joint's noise (Henderson et al. 2010;
Clairon et al. 2017). ``oe`` is West et al.'s fit: Nelder-Mead on the mean
simulation error. The recursion is a first-order filter, so each residual
evaluation is a few numpy and ``lfilter`` calls over all experiments at once
(experiments of similar length share one padded 2-D array), and the map is
evaluated once per distinct command level.

Map families: ``sdp`` (eq. (5)), ``pwl`` (monotone piecewise-linear, for valves
that do not follow eq. (5)) and ``poly`` (the second paper's polynomial gain).

"""

from __future__ import annotations

from dataclasses import dataclass, field
import math
from typing import Callable, Sequence

from hydro_sdp.core.arrays import FloatArray
from hydro_sdp.core.delay import LevelSpeed
from hydro_sdp.core.errors import DataError
from hydro_sdp.core.experiments import Experiment
from hydro_sdp.core.static_maps import PolyMap, PwlMap, SdpMap, StaticMap
import numpy as np
import numpy.typing as npt
from scipy.optimize import least_squares, minimize
from scipy.signal import lfilter

RateFunction = Callable[[FloatArray], FloatArray]


class FitData:
    """
    Experiments arranged for fast residual evaluation.

    Parameters
    ----------
    experiments : sequence of Experiment
        The experiments.
    delay : int
        Delay, samples.
    dt : float
        Sample period, s.

    """

    def __init__(self, experiments: Sequence[Experiment], delay: int, dt: float) -> None:
        if not experiments:
            raise DataError('no experiments to fit')
        self.experiments = tuple(experiments)
        self.delay = delay
        self.dt = dt
        delayed_all, observed_all, initial_all = [], [], []
        for experiment in experiments:
            k = np.arange(experiment.start + 1, experiment.y.size)
            delayed_all.append(experiment.v[np.maximum(k - delay, 0)])
            observed_all.append(experiment.y[k])
            initial_all.append(float(experiment.y[experiment.start]))
        self.levels, inverse = np.unique(np.concatenate(delayed_all), return_inverse=True)
        self.samples = int(inverse.size)
        lengths = np.array([d.size for d in delayed_all])
        # Pad experiments of similar length (same power of two) into one 2-D block.
        sizes = 2 ** np.ceil(np.log2(np.maximum(lengths, 1))).astype(int)
        offsets = np.r_[0, np.cumsum(lengths)]
        self.buckets = []
        for size in np.unique(sizes):
            members = np.flatnonzero(sizes == size)
            width = int(lengths[members].max())
            index = np.zeros((members.size, width), dtype=np.int64)
            observed = np.zeros((members.size, width))
            mask = np.zeros((members.size, width), dtype=bool)
            for row, member in enumerate(members):
                length = lengths[member]
                index[row, :length] = inverse[offsets[member]:offsets[member] + length]
                observed[row, :length] = observed_all[member]
                observed[row, length:] = observed_all[member][-1] if length else 0.0
                mask[row, :length] = True
            initial = np.array([initial_all[m] for m in members])
            self.buckets.append((members, index, observed, mask, initial))

    def increments(self, rate: RateFunction) -> list[FloatArray]:
        """Per bucket, ``dt rate(v_{k-tau})`` with padding set to zero."""
        per_level = self.dt * rate(self.levels)
        return [np.where(mask, per_level[index], 0.0) for _, index, _, mask, _ in self.buckets]

    def residuals(self, rate: RateFunction, beta: float = 0.0) -> FloatArray:
        """
        Prediction errors ``Z`` of every sample, concatenated (regret-regression form).

        Parameters
        ----------
        rate : callable
            The map, commands to deg/s.
        beta : float
            Gain on the state residuals (0: simulation error).

        Returns
        -------
        FloatArray
            One residual per predicted sample.

        """
        out = []
        for (_, _, observed, mask, initial), q in zip(self.buckets, self.increments(rate)):
            if beta == 0.0:
                predicted = initial[:, None] + np.cumsum(q, axis=1)
            else:
                a = 1.0 - beta
                drive = a * q + beta * observed
                state, _ = lfilter([1.0], [1.0, -a], drive, axis=1, zi=(a * initial)[:, None])
                previous = np.concatenate([initial[:, None], state[:, :-1]], axis=1)
                predicted = previous + q
            out.append((observed - predicted)[mask])
        return np.concatenate(out)

    def simulation_mae(self, rate: RateFunction) -> float:
        """Mean absolute simulation error over all predicted samples, degrees."""
        return float(np.mean(np.abs(self.residuals(rate, 0.0))))

    def mean_experiment_sse(self, rate: RateFunction) -> float:
        """Mean over experiments of the summed squared simulation error (West et al.)."""
        return float(np.sum(self.residuals(rate, 0.0) ** 2) / len(self.experiments))


@dataclass(frozen=True, eq=False)
class MapFit:
    """
    A fitted static map.

    Parameters
    ----------
    static_map : StaticMap
        The map.
    method : str
        ``rr``, ``oe`` or ``points``.
    beta : float
        Regret-regression gain (0 for ``oe``).
    cost : float
        Sum of squared residuals at the optimum.
    standard_errors : dict
        Standard error of each parameter, by model-file name.
    evaluations : int
        Objective evaluations used.
    starts : int
        Starting points tried.

    """

    static_map: StaticMap
    method: str
    beta: float
    cost: float
    standard_errors: dict = field(default_factory=dict)
    evaluations: int = 0
    starts: int = 1


def sdp_rate(x: FloatArray) -> RateFunction:
    """Return the eq. (5) map for ``x = (vn, cn, a3, vp, cp, a6)`` (rates in deg/s)."""
    v_neg, c_neg, low, v_pos, c_pos, high = (float(value) for value in x[:6])

    def rate(v: FloatArray) -> FloatArray:
        return (v_neg * -np.expm1(c_neg * np.minimum(v - low, 0.0))
                + v_pos * -np.expm1(-c_pos * np.maximum(v - high, 0.0)))
    return rate


def initial_sdp(points: Sequence[LevelSpeed], rest: float) -> FloatArray:
    """
    Return starting values of ``(vn, cn, a3, vp, cp, a6)`` from per-level speeds.

    The edges lie between the outermost still level and the innermost moving
    one on each side; the saturation speeds a little beyond the fastest points;
    then the exponential is fitted to the points themselves.

    Parameters
    ----------
    points : sequence of LevelSpeed
        Mean speeds per command level.
    rest : float
        Rest command.

    Returns
    -------
    FloatArray
        Starting parameters.

    """
    check_excitation(points, rest)
    levels = np.array([p.level for p in points])
    speeds = np.array([p.speed for p in points])
    errors = np.array([p.standard_error for p in points])
    peak = np.max(np.abs(speeds))
    moving = _moving(speeds, errors)
    scale = max(np.max(np.abs(levels - rest)), 1e-9)
    guess = []
    for sign in (-1.0, 1.0):
        side = sign * (levels - rest) > 0
        go = side & moving & (sign * speeds > 0)
        still = side & ~moving
        inner_moving = np.min(sign * (levels[go] - rest))
        outer_still = np.max(sign * (levels[still] - rest), initial=0.0)
        outer_still = outer_still if outer_still < inner_moving else 0.0
        edge = rest + sign * 0.5 * (outer_still + inner_moving)
        fastest = sign * np.max(sign * speeds[go])
        guess.append((1.2 * fastest, 3.0 / scale, edge))
    x0 = np.array([guess[0][0], guess[0][1], guess[0][2], guess[1][0], guess[1][1],
                   guess[1][2]])
    weights = 1.0 / np.maximum(errors, 1e-3 * peak)
    lower, upper = sdp_bounds(levels, speeds, rest)
    x0 = np.clip(x0, lower[:6], upper[:6])
    result = least_squares(lambda x: (sdp_rate(x)(levels) - speeds) * weights, x0,
                           bounds=(lower[:6], upper[:6]), x_scale='jac')
    return result.x


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

    Parameters
    ----------
    points : sequence of LevelSpeed
        Mean speeds per command level.
    rest : float
        Rest command.

    Raises
    ------
    DataError
        If the joint never moves, or moves in one direction only.

    """
    if not points:
        raise DataError('no excitation: no command level was held long enough to measure a '
                        'speed')
    speeds = np.array([p.speed for p in points])
    errors = np.array([p.standard_error for p in points])
    levels = np.array([p.level for p in points])
    moving = _moving(speeds, errors)
    if not np.any(moving & (np.abs(speeds) > 0.05 * np.max(np.abs(speeds)))):
        raise DataError('no excitation: the joint never moves (are all commands inside the '
                        'dead-zone?)')
    up = np.any(moving & (speeds > 0) & (levels > rest))
    down = np.any(moving & (speeds < 0) & (levels < rest))
    if not (up and down):
        direction = 'positive' if up else 'negative'
        raise DataError(f'the joint moves in the {direction} direction only: the map needs '
                        'commands on both sides of rest that move it')


def _moving(speeds: FloatArray, errors: FloatArray) -> npt.NDArray[np.bool_]:
    # One test of "this level moves the joint" for the checks and the starting values, so
    # data the checks accept always give the starting values something on both sides.
    peak = max(float(np.max(np.abs(speeds))), 1e-9)
    return (np.abs(speeds) > np.maximum(3.0 * errors, 1e-9)) & (np.abs(speeds) > 0.02 * peak)


def _covariance_errors(jacobian: FloatArray, cost: float, samples: int) -> FloatArray:
    parameters = jacobian.shape[1]
    variance = 2.0 * cost / max(samples - parameters, 1)
    try:
        covariance = variance * np.linalg.pinv(jacobian.T @ jacobian)
    except np.linalg.LinAlgError:
        return np.full(parameters, np.inf)
    return np.sqrt(np.clip(np.diag(covariance), 0.0, None))


SDP_NAMES = ('saturation_velocity[0]', 'curvature[0]', 'dead_zone[0]',
             'saturation_velocity[1]', 'curvature[1]', 'dead_zone[1]')


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


def fit_sdp(data: FitData, points: Sequence[LevelSpeed], rest: float, *, method: str = 'rr',
            starts: int = 4, polish: FitData | None = None) -> MapFit:
    """
    Fit eq. (5) of West et al. by regret-regression or by output error.

    Regret-regression is solved by Levenberg-Marquardt (MINPACK) on logs of the
    positive quantities and a logit of ``beta``, which keeps the signs, the
    ordering ``a3 <= rest <= a6`` and ``0 < beta < 1`` without bounds.

    Parameters
    ----------
    data : FitData
        The experiments.
    points : sequence of LevelSpeed
        Per-level speeds, for the starting values.
    rest : float
        Rest command.
    method : str
        ``rr`` (least squares on the regret-regression residuals, ``beta``
        estimated) or ``oe`` (Nelder-Mead on the mean simulation error).
    starts : int
        Number of starting points (the curvatures are varied around the start).
    polish : FitData or None
        Larger data set: the starts run on ``data`` (a sample of it) and the best
        is refined on ``polish``.

    Returns
    -------
    MapFit
        The fitted ``sdp`` map with standard errors.

    """
    if method not in ('rr', 'oe'):
        raise DataError(f"method must be 'rr' or 'oe', got {method!r}")
    base = initial_sdp(points, rest)
    levels = np.array([p.level for p in points])
    lower, upper = sdp_bounds(levels, np.array([p.speed for p in points]), rest)
    scale = max(float(np.max(np.abs(levels - rest))), 1e-9)
    factors = [1.0, 0.5, 2.0, 4.0, 0.25][:max(starts, 1)]

    def rr_fit(fit_data: FitData, free: FloatArray):
        def residuals(p: FloatArray) -> FloatArray:
            x = _to_natural(p, rest)
            return fit_data.residuals(sdp_rate(x), x[6])
        return least_squares(residuals, free, method='lm', x_scale=1.0)

    def oe_fit(fit_data: FitData, x0: FloatArray, iterations: int):
        return minimize(lambda x: fit_data.mean_experiment_sse(sdp_rate(x)), x0,
                        method='Nelder-Mead', bounds=list(zip(lower[:6], upper[:6])),
                        options={'maxiter': iterations, 'maxfev': iterations, 'xatol': 1e-7,
                                 'fatol': 1e-12, 'adaptive': True})

    best = None
    evaluations = 0
    for factor in factors:
        x0 = base.copy()
        x0[[1, 4]] *= factor
        if method == 'rr':
            result = rr_fit(data, _to_free(np.r_[x0, 0.5], rest, scale))
            cost = float(result.cost)
        else:
            result = oe_fit(data, np.clip(x0, lower[:6], upper[:6]), 6000)
            cost = 0.5 * float(np.sum(data.residuals(sdp_rate(result.x)) ** 2))
        evaluations += result.nfev
        if best is None or cost < best[0]:
            best = (cost, result)
    cost, result = best
    if polish is not None:
        data = polish
        result = rr_fit(data, result.x) if method == 'rr' else oe_fit(data, result.x, 2000)
        evaluations += result.nfev
    if method == 'rr':
        x = _to_natural(result.x, rest)
        cost = float(result.cost)
        jacobian = np.asarray(result.jac) / _natural_derivative(result.x)
    else:
        x = np.r_[result.x, 0.0]
        cost = 0.5 * float(np.sum(data.residuals(sdp_rate(x)) ** 2))
        jacobian = _numeric_jacobian(lambda p: data.residuals(sdp_rate(p)), x[:6])
    errors = _covariance_errors(jacobian, cost, data.samples)
    names = SDP_NAMES + (('beta',) if method == 'rr' else ())
    static_map = SdpMap(dead_zone=(float(x[2]), float(x[5])),
                        saturation_velocity=(float(x[0]), float(x[3])),
                        curvature=(float(x[1]), float(x[4])))
    return MapFit(static_map, method, float(x[6]), cost,
                  dict(zip(names, errors.tolist())), evaluations, len(factors))


def _numeric_jacobian(function: Callable[[FloatArray], FloatArray], x: FloatArray) -> FloatArray:
    base = function(x)
    columns = []
    for i in range(x.size):
        step = 1e-6 * max(abs(x[i]), 1e-3)
        shifted = x.copy()
        shifted[i] += step
        columns.append((function(shifted) - base) / step)
    return np.column_stack(columns)


def fit_pwl(data: FitData, points: Sequence[LevelSpeed], rest: float,
            dead_zone: tuple[float, float], *, knots_per_side: int = 4) -> MapFit:
    """
    Fit a monotone piecewise-linear map by regret-regression.

    The zero-speed plateau spans ``dead_zone``; beyond each edge, knots sit at
    quantiles of the commands used, and the speeds between knots are cumulative
    non-negative increments, so the map stays monotone.

    Parameters
    ----------
    data : FitData
        The experiments.
    points : sequence of LevelSpeed
        Per-level speeds, for the starting values.
    rest : float
        Rest command.
    dead_zone : tuple[float, float]
        Edges of the zero-speed plateau.
    knots_per_side : int
        Knots beyond each edge.

    Returns
    -------
    MapFit
        The fitted ``pwl`` map.

    """
    low, high = dead_zone
    levels = data.levels
    knots_neg = np.unique(np.quantile(levels[levels < low], np.linspace(0, 1, knots_per_side))) \
        if np.any(levels < low) else np.array([low - 1.0])
    knots_pos = np.unique(np.quantile(levels[levels > high], np.linspace(0, 1, knots_per_side))) \
        if np.any(levels > high) else np.array([high + 1.0])
    knots = np.r_[knots_neg, low, high, knots_pos]
    if high <= low:
        knots = np.r_[knots_neg, low, knots_pos]
    n_neg, n_pos = knots_neg.size, knots_pos.size
    point_levels = np.array([p.level for p in points])
    point_speeds = np.array([p.speed for p in points])
    target = np.interp(knots, point_levels, point_speeds)

    def speeds_of(x: FloatArray) -> FloatArray:
        negative = -np.cumsum(x[:n_neg][::-1])[::-1]       # outward from the lower edge
        positive = np.cumsum(x[n_neg:n_neg + n_pos])
        zeros = np.zeros(knots.size - n_neg - n_pos)
        return np.r_[negative, zeros, positive]

    x0 = np.r_[np.maximum(-np.diff(np.r_[target[:n_neg], 0.0])[::-1][::-1], 1e-6),
               np.maximum(np.diff(np.r_[0.0, target[-n_pos:]]), 1e-6), 0.5]
    lower = np.r_[np.zeros(n_neg + n_pos), 0.0]
    upper = np.r_[np.full(n_neg + n_pos, np.inf), 1.0]
    result = least_squares(
        lambda x: data.residuals(lambda v: np.interp(v, knots, speeds_of(x)), x[-1]),
        np.clip(x0, lower, upper), bounds=(lower, upper), x_scale='jac')
    speeds = speeds_of(result.x)
    static_map = PwlMap(knots=tuple(knots.tolist()), speeds=tuple(speeds.tolist()))
    errors = _covariance_errors(result.jac, result.cost, data.samples)
    return MapFit(static_map, 'rr', float(result.x[-1]), float(result.cost),
                  {'beta': float(errors[-1])}, int(result.nfev))


def fit_poly(points: Sequence[LevelSpeed], rest: float, *, degree: int = 3) -> MapFit:
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


def sdp_from_alpha_vector(x: FloatArray) -> SdpMap:
    """Build an :class:`SdpMap` from ``(vn, cn, a3, vp, cp, a6)`` (rates in deg/s)."""
    return SdpMap(dead_zone=(float(x[2]), float(x[5])),
                  saturation_velocity=(float(x[0]), float(x[3])),
                  curvature=(float(x[1]), float(x[4])))


def is_finite_map(static_map: StaticMap) -> bool:
    """Whether a map gives finite speeds over a wide command range."""
    probe = np.linspace(-1e3, 1e3, 101)
    return bool(np.all(np.isfinite(static_map.rate(probe)))) and not math.isnan(
        float(static_map.rate(np.array([0.0]))[0]))

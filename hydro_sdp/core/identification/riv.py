"""
Refined instrumental variable estimation of discrete transfer functions (SRIV/RIV).

The reasoning is in docs/methods.md sections 1.4, 1.6.

"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Sequence
import warnings

from hydro_sdp.core.arrays import FloatArray
from hydro_sdp.core.errors import DataError
import numpy as np
from scipy.signal import lfilter


class NotConvergedWarning(UserWarning):
    """An iterative estimator stopped at its iteration limit."""


@dataclass(frozen=True, eq=False)
class TfEstimate:
    """
    An estimated discrete transfer function with its diagnostics.

    Attributes
    ----------
    a : FloatArray
        Full denominator ``[1, a_1, .., a_n]`` (known factor included).
    b : FloatArray
        Numerator ``[b_0, .., b_m]`` acting on ``u_{k-delay}``.
    delay : int
        Pure delay, samples.
    parameters : FloatArray
        The estimated parameters ``[a'_1 .. a'_n', b_0 .. b_m]`` (without the known factor).
    covariance : FloatArray
        ``P* = sigma2 [sum phi^ phi^']^-1`` of ``parameters``.
    rt2_diff : float
        The same on the differenced output (informative for integrating outputs).
    yic : float
        Young information criterion (more negative is better).
    fit : float
        NRMSE fit, percent.
    converged : bool
        Whether the relative parameter change fell below the tolerance.
    warnings : tuple[str, ...]
        Anything the user should know (not converged, unstable model...).
    simulated : tuple[FloatArray, ...]
        Noise-free model output per experiment.
    noise_ar : FloatArray
        AR noise polynomial ``[1, c_1 ..]`` (RIV), ``[1]`` for SRIV.

    """

    a: FloatArray
    b: FloatArray
    delay: int
    parameters: FloatArray
    covariance: FloatArray
    sigma2: float
    rt2: float
    rt2_diff: float
    yic: float
    fit: float
    iterations: int
    converged: bool
    warnings: tuple[str, ...] = ()
    simulated: tuple[FloatArray, ...] = field(default=(), repr=False)
    noise_ar: FloatArray = field(default_factory=lambda: np.ones(1))

    @property
    def standard_errors(self) -> FloatArray:
        """Return the standard errors of ``parameters``."""
        return np.sqrt(np.diag(self.covariance))

    @property
    def structure(self) -> tuple[int, int, int]:
        """Return ``[na, nb, nd]`` as CAPTAIN writes it: orders and delay."""
        return len(self.a) - 1, len(self.b), self.delay


def _stabilise(a: FloatArray) -> FloatArray:
    """Reflect roots of ``z^n + a_1 z^(n-1) + ..`` outside the unit circle (CAPTAIN Stb=1)."""
    if a.size <= 1:
        return a
    roots = np.roots(a)
    outside = np.abs(roots) > 1.0
    if not outside.any():
        return a
    roots[outside] = 1.0 / np.conj(roots[outside])
    return np.real(np.poly(roots))


def _regressors(y: FloatArray, u: FloatArray, n: int, m: int, delay: int) -> FloatArray:
    """Return rows ``[-y_{k-1} .. -y_{k-n}, u_{k-delay} .. u_{k-delay-m}]`` (zeros before 0)."""
    size = y.size
    columns = []
    for i in range(1, n + 1):
        columns.append(-np.r_[np.zeros(min(i, size)), y[:size - i]][:size])
    for j in range(m + 1):
        lag = delay + j
        columns.append(np.r_[np.zeros(min(lag, size)), u[:size - lag]][:size])
    return np.column_stack(columns) if columns else np.zeros((size, 0))


def _as_experiments(y: FloatArray | Sequence[FloatArray],
                    u: FloatArray | Sequence[FloatArray]) -> list[tuple[FloatArray, FloatArray]]:
    # One experiment may be given as bare arrays, several as sequences of arrays.
    single = isinstance(y, np.ndarray) and y.ndim == 1
    outputs = [y] if single else list(y)
    inputs = [u] if single else list(u)
    pairs = []
    for index, (output, data) in enumerate(zip(outputs, inputs)):
        output = np.asarray(output, dtype=np.float64)
        data = np.asarray(data, dtype=np.float64)
        if output.shape != data.shape or output.ndim != 1:
            raise DataError(f'experiment {index}: y and u must be 1-D of equal length')
        if not (np.all(np.isfinite(output)) and np.all(np.isfinite(data))):
            raise DataError(f'experiment {index}: y or u is not finite')
        pairs.append((output, data))
    if not pairs:
        raise DataError('no experiments to estimate from')
    return pairs


@dataclass(frozen=True, eq=False)
class _IvProblem:
    """The pooled experiments of one estimation and the structure estimated."""

    experiments: list[tuple[FloatArray, FloatArray]]
    n: int
    m: int
    delay: int
    warm_up: int

    @property
    def parameters(self) -> int:
        return self.n + self.m + 1

    def model(self, rho: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Return the auxiliary model ``B/A`` of ``rho``: numerator (delayed), denominator."""
        return np.r_[np.zeros(self.delay), rho[self.n:]], np.r_[1.0, rho[:self.n]]


@dataclass(frozen=True, eq=False)
class _NormalEquations:
    """The IV cross-products summed over the experiments, and the auxiliary model's output."""

    cross: FloatArray
    rhs: FloatArray
    instrument_product: FloatArray
    simulated: list[FloatArray]


def _normal_equations(problem: _IvProblem, prefilter: tuple[FloatArray, FloatArray] | None,
                      rho: FloatArray | None) -> _NormalEquations:
    """Sum the IV cross-products over the experiments, each filtered on its own."""
    n, m, delay, k0 = problem.n, problem.m, problem.delay, problem.warm_up
    size = problem.parameters
    cross = np.zeros((size, size))
    rhs = np.zeros(size)
    instrument_product = np.zeros((size, size))
    simulated = []
    for output, data in problem.experiments:
        if rho is None or prefilter is None:
            x = output
            phi = _regressors(output, data, n, m, delay)[k0:]
            instruments, target = phi, output[k0:]
        else:
            numerator, denominator = problem.model(rho)
            x = lfilter(numerator, denominator, data)
            c_filter, a_filter = prefilter
            y_f = lfilter(c_filter, a_filter, output)
            u_f = lfilter(c_filter, a_filter, data)
            x_f = lfilter(c_filter, a_filter, x)
            phi = _regressors(y_f, u_f, n, m, delay)[k0:]
            instruments = _regressors(x_f, u_f, n, m, delay)[k0:]
            target = y_f[k0:]
        simulated.append(x)
        cross += instruments.T @ phi
        rhs += instruments.T @ target
        instrument_product += instruments.T @ instruments
    return _NormalEquations(cross, rhs, instrument_product, simulated)


def _problem(y: FloatArray | Sequence[FloatArray], u: FloatArray | Sequence[FloatArray], n: int,
             m: int, delay: int, factor: FloatArray, warm_up: int | None) -> _IvProblem:
    """Check the structure and the data; filter the inputs by the known factor's inverse."""
    if n < 0 or m < 0 or delay < 0:
        raise DataError(f'orders and delay must be >= 0, got n={n}, m={m}, delay={delay}')
    experiments = _as_experiments(y, u)
    if factor.size == 0 or factor[0] != 1.0:
        raise DataError('the known factor of A must start with 1')
    # y = B / (A' K) u = B / A' (u / K): filter the input by the known factor's inverse.
    experiments = [(output, lfilter([1.0], factor, data)) for output, data in experiments]
    k0 = max(n, delay + m) if warm_up is None else warm_up
    problem = _IvProblem(experiments, n, m, delay, k0)
    used = sum(max(0, output.size - k0) for output, _ in experiments)
    if used <= problem.parameters + 1:
        raise DataError(f'too few samples ({used}) for {problem.parameters} parameters')
    return problem


def _least_squares_start(problem: _IvProblem) -> FloatArray:
    """Return the least-squares estimate the IV iterations start from."""
    equations = _normal_equations(problem, None, None)
    try:
        start: FloatArray = np.linalg.lstsq(equations.cross, equations.rhs, rcond=None)[0]
    except np.linalg.LinAlgError as error:
        raise DataError(f'the least-squares start failed: {error}') from None
    return start


def _iterate(problem: _IvProblem, rho: FloatArray, noise_order: int, tol: float,
             max_iterations: int) -> tuple[FloatArray, FloatArray, int, bool]:
    """Refine ``rho`` by IV iterations until it stops changing (relative change below ``tol``)."""
    n = problem.n
    noise: FloatArray = np.ones(1)
    iterations = 0
    for iterations in range(1, max_iterations + 1):
        a_hat = _stabilise(np.r_[1.0, rho[:n]])
        rho_stable = np.r_[a_hat[1:], rho[n:]]
        if noise_order > 0:
            simulated = _normal_equations(problem, (noise, a_hat), rho_stable).simulated
            residual = np.concatenate([output - x for (output, _), x in
                                       zip(problem.experiments, simulated)])
            noise = _ar_fit(residual, noise_order)
        equations = _normal_equations(problem, (noise, a_hat), rho_stable)
        new = np.linalg.lstsq(equations.cross, equations.rhs, rcond=None)[0]
        change = float(np.linalg.norm(new - rho)) / max(float(np.linalg.norm(rho)), 1e-12)
        rho = new
        if change < tol:
            return rho, noise, iterations, True
    return rho, noise, iterations, False


def _estimate(problem: _IvProblem, rho: FloatArray, noise: FloatArray, factor: FloatArray,
              iterations: int, converged: bool, notes: list[str]) -> TfEstimate:
    """Return the estimate with its covariance and R_T^2, YIC and Fit (methods 1.8)."""
    n, k0, parameters = problem.n, problem.warm_up, problem.parameters
    a_hat = np.r_[1.0, rho[:n]]
    if n and np.any(np.abs(np.roots(a_hat)) >= 1.0):
        notes.append('the estimated denominator is not stable')
    a_stable = _stabilise(a_hat)
    with np.errstate(over='ignore', invalid='ignore'):
        equations = _normal_equations(problem, (noise, a_stable), np.r_[a_stable[1:], rho[n:]])
    simulated = equations.simulated
    errors = [output[k0:] - x[k0:] for (output, _), x in zip(problem.experiments, simulated)]
    misfit = np.concatenate(errors)
    outputs = np.concatenate([output[k0:] for output, _ in problem.experiments])
    sigma2 = float(np.sum(misfit ** 2) / max(misfit.size - parameters, 1))
    innovation_variance = sigma2
    if noise.size > 1:
        innovations = np.concatenate([lfilter(noise, [1.0], e) for e in errors])
        innovation_variance = float(np.var(innovations))
    try:
        covariance: FloatArray = innovation_variance * np.linalg.inv(equations.instrument_product)
    except np.linalg.LinAlgError:
        covariance = np.full((parameters, parameters), np.inf)
        notes.append('the instrument product matrix is singular')
    variance_y = float(np.var(outputs))
    rt2 = 1.0 - float(np.var(misfit)) / variance_y if variance_y > 0 else float('nan')
    diff_error = np.concatenate([np.diff(e) for e in errors])
    diff_y = np.concatenate([np.diff(output[k0:]) for output, _ in problem.experiments])
    rt2_diff = 1.0 - float(np.var(diff_error)) / float(np.var(diff_y)) \
        if np.var(diff_y) > 0 else float('nan')
    with np.errstate(divide='ignore', invalid='ignore'):
        nevn = float(np.mean(np.diag(covariance) / rho ** 2))
        yic = float(np.log(np.var(misfit) / variance_y) + np.log(nevn))
    norm = np.linalg.norm(outputs - outputs.mean())
    fit = 100.0 * (1.0 - float(np.linalg.norm(misfit)) / float(norm)) if norm > 0 else float('nan')
    return TfEstimate(
        a=np.convolve(a_hat, factor), b=rho[n:].copy(), delay=problem.delay, parameters=rho,
        covariance=covariance, sigma2=sigma2, rt2=rt2, rt2_diff=rt2_diff, yic=yic, fit=fit,
        iterations=iterations, converged=converged, warnings=tuple(notes),
        simulated=tuple(simulated), noise_ar=noise)


def sriv(y: FloatArray | Sequence[FloatArray], u: FloatArray | Sequence[FloatArray], n: int,
         m: int, delay: int, *, known_factor: Sequence[float] = (1.0,), noise_order: int = 0,
         tol: float = 1e-4, max_iterations: int = 20, warm_up: int | None = None) -> TfEstimate:
    """Estimate ``B/A`` by simplified (or, with ``noise_order``, full) refined IV."""
    factor = np.asarray(known_factor, dtype=np.float64)
    problem = _problem(y, u, n, m, delay, factor, warm_up)
    rho, noise, iterations, converged = _iterate(
        problem, _least_squares_start(problem), noise_order, tol, max_iterations)
    notes: list[str] = []
    if not converged:
        notes.append(f'not converged after {max_iterations} iterations')
        warnings.warn(f'SRIV did not converge in {max_iterations} iterations',
                      NotConvergedWarning, stacklevel=2)
    return _estimate(problem, rho, noise, factor, iterations, converged, notes)


def _ar_fit(residual: FloatArray, order: int) -> FloatArray:
    """Least-squares AR polynomial ``[1, c_1 .. c_p]`` of a residual series."""
    rows = np.column_stack([-np.r_[np.zeros(i), residual[:-i]] for i in range(1, order + 1)])
    coefficients = np.linalg.lstsq(rows[order:], residual[order:], rcond=None)[0]
    return np.r_[1.0, coefficients]

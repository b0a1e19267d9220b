"""Proportional-Integral-Plus (PIP) design in non-minimal state space (NMSS) (methods 4.1-4.5)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

from hydro_sdp.core.arrays import FloatArray
from hydro_sdp.core.errors import ConfigurationError
import numpy as np

# Closed-loop poles must land within this distance of the requested ones.
POLE_TOLERANCE = 1e-6


@dataclass(frozen=True)
class DiscretePlant:
    """
    Discrete transfer function ``B(z^-1) / A(z^-1)`` of the plant seen by the controller.

    Parameters
    ----------
    a : tuple[float, ...]
        ``a_1 .. a_n`` of ``A = 1 + a_1 z^-1 + ... + a_n z^-n`` (``n >= 1``).
    b : tuple[float, ...]
        ``b_1 .. b_m`` of ``B = b_1 z^-1 + ... + b_m z^-m``; leading zeros are the delay.

    """

    a: tuple[float, ...]
    b: tuple[float, ...]

    def __post_init__(self) -> None:
        a = tuple(float(x) for x in self.a)
        b = tuple(float(x) for x in self.b)
        if not a:
            raise ConfigurationError('the plant needs at least one denominator coefficient')
        if not b or not any(b):
            raise ConfigurationError('the plant numerator B must have a non-zero coefficient')
        if not all(np.isfinite(a + b)):
            raise ConfigurationError('plant coefficients must be finite')
        object.__setattr__(self, 'a', a)
        object.__setattr__(self, 'b', b)

    @classmethod
    def integrator(cls, delay: int, gain: float = 1.0) -> DiscretePlant:
        """Return ``y_k = y_{k-1} + gain u_{k-delay}``, the plant a PIP-IDZ loop sees."""
        if delay < 1:
            raise ConfigurationError(f'the delay must be at least one sample, got {delay}')
        return cls(a=(-1.0,), b=(0.0,) * (delay - 1) + (float(gain),))

    @property
    def n(self) -> int:
        """Denominator order."""
        return len(self.a)

    @property
    def m(self) -> int:
        """Numerator order (delay included)."""
        return len(self.b)

    @property
    def delay(self) -> int:
        """Pure delay in samples: the index of the first non-zero ``b``."""
        return next(i for i, value in enumerate(self.b, start=1) if value != 0.0)


@dataclass(frozen=True)
class Nmss:
    """
    NMSS form ``x_k = F x_{k-1} + g u_{k-1} + d r_k``, ``y_k = h' x_k``.

    Attributes
    ----------
    F : FloatArray
        State transition matrix, ``(n + m, n + m)``.

    """

    F: FloatArray
    g: FloatArray
    d: FloatArray
    h: FloatArray


def nmss(plant: DiscretePlant) -> Nmss:
    """
    Build the NMSS model of ``plant`` (docs/methods.md section 4.1).

    Returns: matrices of dimension ``n + m``.
    """
    n, m = plant.n, plant.m
    size = n + m
    F = np.zeros((size, size))
    g = np.zeros(size)
    F[0, :n] = -np.asarray(plant.a)
    F[0, n:n + m - 1] = plant.b[1:]
    g[0] = plant.b[0]
    for i in range(1, n):
        F[i, i - 1] = 1.0
    if m > 1:
        g[n] = 1.0
        for j in range(1, m - 1):
            F[n + j, n + j - 1] = 1.0
    F[-1] = -F[0]
    F[-1, -1] = 1.0
    g[-1] = -g[0]
    d = np.zeros(size)
    d[-1] = 1.0
    h = np.zeros(size)
    h[0] = 1.0
    return Nmss(F, g, d, h)


@dataclass(frozen=True)
class PipGains:
    """
    PIP gains: output feedback ``f``, input feedback ``g`` and integral gain ``k_i``.

    Parameters
    ----------
    f : tuple[float, ...]
        ``f_0 .. f_{n-1}``.
    g : tuple[float, ...]
        ``g_1 .. g_{m-1}`` (empty for ``m = 1``).
    k_i : float
        Integral gain ``k_I``.

    """

    f: tuple[float, ...]
    g: tuple[float, ...]
    k_i: float

    def __post_init__(self) -> None:
        f = tuple(float(x) for x in self.f)
        g = tuple(float(x) for x in self.g)
        if not f or not np.all(np.isfinite(f + g + (float(self.k_i),))):
            raise ConfigurationError('PIP gains must be finite, with at least one f')
        object.__setattr__(self, 'f', f)
        object.__setattr__(self, 'g', g)
        object.__setattr__(self, 'k_i', float(self.k_i))

    @property
    def vector(self) -> FloatArray:
        """Return the state-feedback vector ``k = [f, g, -k_I]`` of ``u = -k' x``."""
        return np.r_[self.f, self.g, -self.k_i]

    @classmethod
    def from_vector(cls, k: FloatArray, n: int) -> PipGains:
        """Split a state-feedback vector into PIP gains for a plant of order ``n``."""
        k = np.asarray(k, dtype=np.float64).ravel()
        return cls(f=tuple(k[:n]), g=tuple(k[n:-1]), k_i=float(-k[-1]))


def closed_loop_poles(plant: DiscretePlant, gains: PipGains) -> np.ndarray:
    """
    Eigenvalues of the closed-loop NMSS matrix ``F - g k'``.

    Returns: complex poles, sorted by decreasing magnitude.
    """
    model = nmss(plant)
    k = gains.vector
    if k.size != model.F.shape[0]:
        raise ConfigurationError(f'{k.size} gains for an NMSS model of order {model.F.shape[0]}')
    poles = np.linalg.eigvals(model.F - np.outer(model.g, k))
    return poles[np.argsort(-np.abs(poles), kind='stable')]


def _closed_loop_polynomial(plant: DiscretePlant, theta: FloatArray) -> FloatArray:
    """Coefficients of Delta (A G + B F) + k_I B for theta = [g_1.., f_0.., k_I]."""
    n, m = plant.n, plant.m
    g = np.r_[1.0, theta[:m - 1]]
    f = theta[m - 1:m - 1 + n]
    k_i = theta[-1]
    a = np.r_[1.0, plant.a]
    b = np.r_[0.0, plant.b]
    delta = np.array([1.0, -1.0])
    size = n + m + 1
    out = np.zeros(size)
    first = np.convolve(delta, np.convolve(a, g))
    second = np.convolve(delta, np.convolve(b, f))
    out[:first.size] += first
    out[:second.size] += second
    out[:b.size] += k_i * b
    return out


def _polynomial_from_poles(poles: Sequence[complex]) -> FloatArray:
    coefficients = np.poly(np.asarray(poles, dtype=complex))
    if np.max(np.abs(coefficients.imag)) > 1e-9:
        raise ConfigurationError('complex poles must come in conjugate pairs')
    return np.asarray(coefficients.real, dtype=np.float64)


def pole_assignment(plant: DiscretePlant, poles: Sequence[complex]) -> PipGains:
    """
    PIP gains that place the closed-loop poles at ``poles``.

    ``poles``: ``n + m`` poles, complex ones in conjugate pairs.
    """
    n, m = plant.n, plant.m
    poles = [complex(p) for p in poles]
    if len(poles) != n + m:
        raise ConfigurationError(f'this plant needs {n + m} poles (n + m = {n} + {m}), '
                                 f'got {len(poles)}')
    if any(abs(p) >= 1.0 for p in poles):
        raise ConfigurationError('requested poles must lie inside the unit circle')
    target = _polynomial_from_poles(poles)
    unknowns = n + m
    base = _closed_loop_polynomial(plant, np.zeros(unknowns))
    matrix = np.column_stack([
        _closed_loop_polynomial(plant, np.eye(unknowns)[i]) - base for i in range(unknowns)])
    rhs = target - base
    # Row 0 (the leading 1) holds for any gains; the other rows fix the unknowns.
    system, values = matrix[1:], rhs[1:]
    if np.linalg.matrix_rank(system) < unknowns:
        raise ConfigurationError('the plant is not controllable (A and B share a factor)')
    theta = np.linalg.solve(system, values)
    gains = PipGains(f=tuple(theta[m - 1:m - 1 + n]), g=tuple(theta[:m - 1]), k_i=theta[-1])
    check_poles(plant, gains, poles)
    return gains


def check_poles(plant: DiscretePlant, gains: PipGains, poles: Sequence[complex]) -> None:
    """Raise :class:`ConfigurationError` unless ``gains`` give the closed-loop ``poles``."""
    achieved = closed_loop_poles(plant, gains)
    wanted = np.asarray(poles, dtype=complex)
    # Repeated poles spread as the root of the tolerance, so compare characteristic polynomials.
    difference = np.max(np.abs(np.poly(achieved) - np.poly(wanted)))
    if difference > POLE_TOLERANCE:
        raise ConfigurationError(f'closed-loop poles {np.round(achieved, 6)} differ from the '
                                 f'requested {np.round(wanted, 6)}')


@dataclass(frozen=True)
class LqWeights:
    """
    Diagonal LQ weights in the True Digital Control convention.

    Attributes
    ----------
    w_u : float
        Total weight on the input states and the input.

    """

    w_y: float = 1.6567e-3
    w_u: float = 1.0
    w_e: float = 4.1993e-5

    def __post_init__(self) -> None:
        if not (self.w_y >= 0.0 and self.w_u > 0.0 and self.w_e > 0.0):
            raise ConfigurationError(f'LQ weights need w_y >= 0, w_u > 0 and w_e > 0, got '
                                     f'{self.w_y}, {self.w_u}, {self.w_e}')


def lq_design(plant: DiscretePlant, weights: LqWeights = LqWeights()) -> PipGains:
    """LQ-optimal PIP gains from the discrete algebraic Riccati equation."""
    from scipy.linalg import solve_discrete_are   # here: only LQ designs need scipy
    model = nmss(plant)
    n, m = plant.n, plant.m
    q = np.r_[np.full(n, weights.w_y / n), np.full(m - 1, weights.w_u / m), weights.w_e]
    r = np.array([[weights.w_u / m]])
    g = model.g.reshape(-1, 1)
    try:
        P = solve_discrete_are(model.F, g, np.diag(q), r)
    except (np.linalg.LinAlgError, ValueError) as error:
        raise ConfigurationError(f'the LQ Riccati equation has no solution: {error}') from None
    k = np.linalg.solve(r + g.T @ P @ g, g.T @ P @ model.F).ravel()
    gains = PipGains.from_vector(k, n)
    poles = closed_loop_poles(plant, gains)
    if np.max(np.abs(poles)) >= 1.0:
        raise ConfigurationError(f'the LQ design is not stable (poles {np.round(poles, 4)})')
    return gains

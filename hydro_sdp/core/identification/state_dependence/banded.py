"""
The fixed-interval smoother of a random-walk parameter as a banded least-squares problem.

The reasoning is in docs/methods.md section 14.2.

"""

from __future__ import annotations

from dataclasses import dataclass
import math

from hydro_sdp.core.arrays import FloatArray
from hydro_sdp.core.errors import DataError
from hydro_sdp.core.identification.state_dependence.random_walk import (
    difference, GroupStats, order_of, STENCILS)
import numpy as np
from scipy.linalg import LinAlgError
from scipy.linalg.lapack import dpbtrf, dpbtrs


@dataclass(frozen=True, eq=False)
class BandedFit:
    """
    The smoothed parameter at one NVR.

    Attributes
    ----------
    estimate : FloatArray
        Smoothed parameter per group.
    neg2_log_likelihood : float
        ``-2 log L`` (diffuse, or with the given prior).
    factor : FloatArray
        Lower banded Cholesky factor of ``A`` (for more right-hand sides).
    residual_sum : float
        ``sum (z - x p)^2`` at the estimate.

    """

    estimate: FloatArray
    sigma2: float
    neg2_log_likelihood: float
    factor: FloatArray
    residual_sum: float
    nvr: float

    def solve(self, moment: FloatArray) -> FloatArray:
        """Return ``A^{-1} moment`` (columns: several right-hand sides at once)."""
        return banded_solve(self.factor, moment)

    def variance(self) -> FloatArray:
        """Return ``diag(A^{-1})``: the smoothed variances normalised by ``sigma^2``."""
        return selected_inverse_diagonal(self.factor)

    def standard_error(self) -> FloatArray:
        """Return the standard error of the smoothed parameter per group."""
        return np.sqrt(self.variance() * self.sigma2)


def banded_factor(bands: FloatArray) -> FloatArray:
    """
    Return the lower banded Cholesky factor of ``bands`` (lower banded storage).

    Raises LinAlgError if the matrix is not positive definite.
    """
    factor, info = dpbtrf(bands, lower=1)
    if info > 0:
        raise LinAlgError(f'{info}-th leading minor not positive definite')
    if info < 0:
        raise ValueError(f'illegal value in argument {-info} of dpbtrf')
    return np.asarray(factor)


def banded_solve(factor: FloatArray, rhs: FloatArray) -> FloatArray:
    """Return ``A^{-1} rhs`` from the factor of :func:`banded_factor` (LAPACK ``dpbtrs``)."""
    solution, info = dpbtrs(factor, rhs, lower=1)
    if info != 0:
        raise ValueError(f'illegal value in argument {-info} of dpbtrs')
    return np.asarray(solution)


def penalty_bands(groups: int, kind: str) -> FloatArray:
    """Return ``D'D`` in lower banded storage: row ``i`` holds the ``i``-th subdiagonal."""
    stencil = STENCILS[kind]
    d = len(stencil) - 1
    bands = np.zeros((d + 1, groups))
    rows = groups - d
    if rows <= 0:
        return bands
    # Each row of D adds c_s c_t at (i + t, i + s), t >= s: subdiagonal t - s, column i + s.
    for s, cs in enumerate(stencil):
        for t in range(s, d + 1):
            bands[t - s, s:s + rows] += cs * stencil[t]
    return bands


def _prior_bands(groups: int, kind: str, prior: float) -> FloatArray:
    """Return the initial state's precision ``1 / prior`` in the parameters' terms, banded."""
    bands = np.zeros((order_of(kind) + 1, groups))
    bands[0, 0] = 1.0 / prior
    if order_of(kind) == 2:
        # (p_0, s_0) ~ N(0, prior I) with s_0 = p_1 - p_0: p_0^2 + (p_1 - p_0)^2.
        bands[0, 0] += 1.0 / prior
        bands[0, 1] = 1.0 / prior
        bands[1, 0] = -1.0 / prior
    return bands


def fit_banded(stats: GroupStats, kind: str, nvr: float, *,
               prior: float | None = None, dd_bands: FloatArray | None = None) -> BandedFit:
    """
    Smooth the parameter at a given NVR by the banded normal equations.

    ``stats``: sums of the observations per group.
    ``nvr``: noise variance ratio (> 0).
    ``prior``: variance of the initial state normalised by ``sigma^2``; None: diffuse.
    ``dd_bands``: ``penalty_bands(stats.groups, kind)`` when the caller has it (a search over the
    NVR builds it once); None: built here.
    """
    d = order_of(kind)
    M = stats.groups
    if not (math.isfinite(nvr) and nvr > 0.0):
        raise DataError(f'nvr must be a positive number, got {nvr}')
    if M <= d:
        raise DataError(f'{M} distinct state values: an {kind} walk needs more than {d}')
    bands = (penalty_bands(M, kind) if dd_bands is None else dd_bands) / nvr
    bands[0] += stats.weight
    if prior is not None:
        bands = bands + _prior_bands(M, kind, prior)
    try:
        factor = banded_factor(bands)
    except LinAlgError:
        raise DataError('the regressor is zero at too many state values to smooth along '
                        'them') from None
    # Solved for the offset from the reference, a constant the walk's steps do not see;
    # a proper prior's precision takes the constant at its first row only (both walks).
    moment = stats.moment
    if prior is not None and stats.reference != 0.0:
        moment = moment.copy()
        moment[0] -= stats.reference / prior
    offset = banded_solve(factor, moment)
    estimate = stats.reference + offset
    residual = stats.offset_residual_sum(offset)
    penalty = float(np.sum(difference(offset, kind) ** 2)) / nvr
    if prior is not None:
        start = estimate[0] ** 2 + ((estimate[1] - estimate[0]) ** 2 if d == 2 else 0.0)
        penalty += start / prior
    dof = stats.count if prior is not None else stats.count - d
    if dof <= 0:
        raise DataError(f'{stats.count} observations: too few to smooth an {kind} walk')
    sigma2 = max(residual + penalty, 0.0) / dof
    if sigma2 <= 0.0:
        raise DataError('the observations are fitted exactly: no noise to weigh the walk by')
    log_det = 2.0 * float(np.sum(np.log(factor[0])))
    neg2 = dof * (math.log(2.0 * math.pi * sigma2) + 1.0) + log_det + (M - d) * math.log(nvr)
    if prior is not None:
        neg2 += d * math.log(prior)
    return BandedFit(estimate, sigma2, neg2, factor, residual, nvr)


@dataclass(frozen=True, eq=False)
class FlatFit:
    """
    The walk's limit at zero NVR: a constant (``rw``) or a line in rank (``irw``).

    Attributes
    ----------
    estimate : FloatArray
        Parameter per group.
    coefficients : FloatArray
        Level (and slope per rank) of the fit.
    covariance : FloatArray
        Their covariance, ``sigma^2 (N'WN)^{-1}``.
    neg2_log_likelihood : float
        ``-2 log L``, the limit of the diffuse likelihood of :func:`fit_banded`.
    residual_sum : float
        ``sum (z - x p)^2``.

    """

    estimate: FloatArray
    coefficients: FloatArray
    covariance: FloatArray
    sigma2: float
    neg2_log_likelihood: float
    residual_sum: float

    def standard_error(self, basis: FloatArray) -> FloatArray:
        """Return the standard error of the fit at the rows of ``basis``."""
        return np.sqrt(np.einsum('ij,jk,ik->i', basis, self.covariance, basis))


def null_basis(groups: int, kind: str) -> FloatArray:
    """Return the walks' zero-NVR basis: ``[1]`` (``rw``) or ``[1, j]`` (``irw``), per group."""
    rank = np.arange(groups, dtype=np.float64)
    return np.ones((groups, 1)) if order_of(kind) == 1 else np.column_stack([np.ones(groups),
                                                                            rank])


def fit_flat(stats: GroupStats, kind: str) -> FlatFit:
    """
    Fit the walk at zero NVR: weighted least squares on its null space.

    ``stats``: sums of the observations per group.
    """
    d = order_of(kind)
    basis = null_basis(stats.groups, kind)
    normal = np.einsum('ij,i,ik->jk', basis, stats.weight, basis)
    try:
        inverse = np.linalg.inv(normal)
        sign, log_det = np.linalg.slogdet(normal)
    except np.linalg.LinAlgError:
        sign = 0.0
    if sign <= 0.0 or stats.count <= d:
        raise DataError('the regressor does not excite the parameter (all zero or one value)')
    coefficients = inverse @ np.einsum('ij,i->j', basis, stats.moment)
    offset = np.einsum('ij,j->i', basis, coefficients)
    residual = stats.offset_residual_sum(offset)
    # The basis's first column is the constant: the reference is part of the level.
    coefficients[0] += stats.reference
    estimate = stats.reference + offset
    sigma2 = max(residual, 0.0) / (stats.count - d)
    if sigma2 <= 0.0:
        raise DataError('the observations are fitted exactly: no noise to weigh the walk by')
    neg2 = (stats.count - d) * (math.log(2.0 * math.pi * sigma2) + 1.0) + float(log_det)
    return FlatFit(estimate, coefficients, sigma2 * inverse, sigma2, neg2, residual)


def selected_inverse_diagonal(factor: FloatArray) -> FloatArray:
    """
    Return ``diag(A^{-1})`` from the lower banded Cholesky factor of ``A``.

    ``factor``: lower banded factor, shape ``(b + 1, M)`` with ``b`` 1 or 2.
    """
    b = factor.shape[0] - 1
    M = factor.shape[1]
    diag = factor[0].tolist()
    sub1 = factor[1].tolist()
    out = [0.0] * M
    if b == 1:
        s11 = 0.0           # Sigma_{j+1, j+1}
        for j in range(M - 1, -1, -1):
            ljj = diag[j]
            if j == M - 1:
                s11 = 1.0 / (ljj * ljj)
            else:
                l1 = sub1[j]
                s10 = -l1 * s11 / ljj
                s11 = (1.0 / ljj - l1 * s10) / ljj
            out[j] = s11
        return np.array(out)
    if b != 2:
        raise DataError(f'bandwidth {b}: only 1 (rw) and 2 (irw) are supported')
    sub2 = factor[2].tolist()
    # Window of Sigma over rows j+1, j+2: a = S(j+1,j+1), c = S(j+2,j+1), e = S(j+2,j+2).
    a = c = e = 0.0
    for j in range(M - 1, -1, -1):
        ljj = diag[j]
        l1 = sub1[j] if j + 1 < M else 0.0
        l2 = sub2[j] if j + 2 < M else 0.0
        s20 = -(l1 * c + l2 * e) / ljj
        s10 = -(l1 * a + l2 * c) / ljj
        s00 = (1.0 / ljj - l1 * s10 - l2 * s20) / ljj
        out[j] = s00
        a, c, e = s00, s10, a
    return np.array(out)

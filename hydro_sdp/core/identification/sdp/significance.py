"""
Whether a parameter's dependence on a state is significant, with autocorrelated residuals.

The statistic is the likelihood ratio of the dependence, ``LR = -2 log L(0) -
min_nvr -2 log L(nvr)``: how much more likely the data are with the parameter
following the state (its NVR chosen by the data) than with it constant. Its
null distribution comes from a dependent wild bootstrap (Shao 2010): the
residuals of the model with the parameter held constant, at the term's samples
in time order, are cut into blocks
longer than their correlation and each block's sign is flipped at random; the
flipped residuals are smoothed along the same state, the NVR chosen again by
the same scan, and their LR counted. Blocks keep the residuals'
autocorrelation and their size where they occur (the noise of a fast motion
stays with it); the signs break any link with the state. A slowly varying
state (the angle, the time since a change) then cannot make autocorrelated
errors look like a dependence: they do so in the replicates too. The NVR is
re-chosen in every replicate (on the coarse scan of
:mod:`hydro_sdp.core.identification.sdp.nvr`, for the data as for the
replicates), since an NVR fitted to the data would make the data's own ratio
look larger than any replicate's.

"""

from __future__ import annotations

from dataclasses import dataclass
import math

from hydro_sdp.core.arrays import FloatArray
from hydro_sdp.core.identification.sdp.banded import (
    banded_factor, banded_solve, null_basis, penalty_bands)
from hydro_sdp.core.identification.sdp.nvr import nvr_range
from hydro_sdp.core.identification.sdp.ordering import coarsened, Ordering
from hydro_sdp.core.identification.sdp.random_walk import GroupStats, inner, order_of
import numpy as np
from scipy import sparse
from scipy.linalg import LinAlgError

#: Autocorrelation below which residuals count as uncorrelated, for the block length.
ACF_CUT = 0.1
#: Fewest blocks a replicate is cut into.
MIN_BLOCKS = 20
#: Replicates drawn at once (a matrix of right-hand sides).
CHUNK = 16
#: Most groups of the state in the test (neighbouring ones pooled beyond), and the NVRs
#: of its scan (every two decades): resolution enough to see a dependence, and the cost
#: of a replicate stays below a millisecond.
TEST_GROUPS = 2000
TEST_SCAN = 8


def block_length(series: FloatArray) -> int:
    """
    Return the block length for a residual series, samples.

    Twice the first lag at which the autocorrelation falls below :data:`ACF_CUT`,
    at least ``n^(1/3)`` (the usual rate of block bootstraps), at most ``n / 20``.

    Parameters
    ----------
    series : FloatArray
        Residuals in time order.

    Returns
    -------
    int
        Samples per block (>= 1).

    """
    values = np.asarray(series, dtype=np.float64)
    n = values.size
    longest = max(1, n // MIN_BLOCKS)
    centred = values - np.mean(values) if n else values
    power = inner(centred, centred)
    if n < 4 or power <= 0.0:
        return min(longest, max(1, int(round(n ** (1.0 / 3.0)))))
    size = 1 << int(math.ceil(math.log2(2 * n)))
    spectrum = np.fft.rfft(centred, size)
    acf = np.fft.irfft(spectrum * np.conj(spectrum), size)[:n] / power
    below = np.flatnonzero(acf[1:longest + 1] < ACF_CUT)
    lag = int(below[0]) + 1 if below.size else longest
    return int(min(longest, max(math.ceil(n ** (1.0 / 3.0)), 2 * lag)))


class LikelihoodRatio:
    """
    The likelihood ratio of a walk against a flat parameter, for many series at once.

    The walk's factor at each NVR of the scan is computed once; each series (a
    column of per-group moments with its sum of squares) is then scored at all
    of them.

    Parameters
    ----------
    weight : FloatArray
        ``sum x^2`` per group.
    count : int
        Observations.
    kind : str
        ``rw`` or ``irw``.

    """

    def __init__(self, weight: FloatArray, count: int, kind: str) -> None:
        self.weight = np.asarray(weight, dtype=np.float64)
        self.count = count
        self.kind = kind
        self.d = order_of(kind)
        groups = self.weight.size
        stats = GroupStats(self.weight, np.zeros(groups), 0.0, count)
        low, high = nvr_range(stats)
        self.factors: list[tuple[float, FloatArray, float]] = []
        penalty = penalty_bands(groups, kind)
        for nvr in np.geomspace(low, high, TEST_SCAN):
            bands = penalty / nvr
            bands[0] += self.weight
            try:
                factor = banded_factor(bands)
            except LinAlgError:
                continue
            log_det = 2.0 * float(np.sum(np.log(factor[0])))
            self.factors.append((float(nvr), factor, log_det + (groups - self.d) * math.log(nvr)))
        basis = null_basis(groups, kind)
        normal = np.einsum('ij,i,ik->jk', basis, self.weight, basis)
        self.basis = basis
        self.normal_inverse = np.linalg.inv(normal)
        self.flat_log_det = float(np.linalg.slogdet(normal)[1])

    def _neg2(self, squares: FloatArray, extra: float) -> FloatArray:
        dof = self.count - self.d
        return dof * (np.log(2.0 * math.pi * np.maximum(squares, 1e-300) / dof) + 1.0) + extra

    def __call__(self, moment: FloatArray, total: FloatArray) -> FloatArray:
        """
        Return the likelihood ratio of each series (columns of ``moment``).

        Parameters
        ----------
        moment : FloatArray
            ``sum x z`` per group, shape ``(M, series)``.
        total : FloatArray
            ``sum z^2`` of each series.

        Returns
        -------
        FloatArray
            ``max(0, -2 log L(flat) - min over the scan of -2 log L(nvr))`` per series.

        """
        projected = np.einsum('ij,ik->jk', self.basis, moment)
        flat_squares = total - np.sum(projected * (self.normal_inverse @ projected), axis=0)
        flat = self._neg2(flat_squares, self.flat_log_det)
        best = np.full(moment.shape[1], np.inf)
        for nvr, factor, extra in self.factors:
            estimate = banded_solve(factor, moment)
            squares = (total - 2.0 * np.sum(estimate * moment, axis=0)
                       + np.sum(self.weight[:, None] * estimate ** 2, axis=0)
                       + np.sum(np.diff(estimate, n=self.d, axis=0) ** 2, axis=0) / nvr)
            best = np.minimum(best, self._neg2(squares, extra))
        return np.maximum(flat - best, 0.0)


@dataclass(frozen=True)
class DependenceTest:
    """
    The bootstrap test of one parameter's dependence on its state.

    Parameters
    ----------
    statistic : float
        Likelihood ratio of the dependence on the data.
    p_value : float
        Share of replicates (with the data) whose ratio reaches it.
    block : int
        Block length, samples.

    """

    statistic: float
    p_value: float
    block: int


def dependence_test(z: FloatArray, residual: FloatArray, x: FloatArray, state: FloatArray,
                    ordering: Ordering, kind: str, *, replicates: int = 199,
                    seed: int = 0) -> DependenceTest:
    """
    Test whether the parameter of ``z = x p(state) + e`` depends on the state.

    Parameters
    ----------
    z : FloatArray
        The term's observations (its partial residual) at every sample.
    residual : FloatArray
        Residuals at every sample of the model with this parameter held constant (the
        null: residuals of the model with the dependence fitted would have lost the
        slow part of autocorrelated errors that the smoother took for it).
    x : FloatArray
        The term's regressor at every sample.
    state : FloatArray
        The state at every sample.
    ordering : Ordering
        The term's groups (its samples, ascending, are the time order); pooled to
        :data:`TEST_GROUPS`.
    kind : str
        ``rw`` or ``irw``.
    replicates : int
        Bootstrap replicates.
    seed : int
        Seed of the signs and block offsets.

    Returns
    -------
    DependenceTest
        The ratio, its p-value and the block length.

    """
    ordering = coarsened(ordering, TEST_GROUPS, state)
    samples = ordering.samples
    xs = np.asarray(x, dtype=np.float64)[samples]
    n = xs.size
    operator = sparse.csr_matrix((xs, (ordering.group, np.arange(n))),
                                 shape=(ordering.groups, n))
    weight = np.bincount(ordering.group, weights=xs * xs,
                         minlength=ordering.groups).astype(np.float64)
    ratio = LikelihoodRatio(weight, n, kind)
    observed = np.asarray(z, dtype=np.float64)[samples]
    statistic = float(ratio(np.asarray(operator @ observed)[:, None],
                            np.array([inner(observed, observed)]))[0])
    e = np.asarray(residual, dtype=np.float64)[samples]
    block = block_length(e)
    if statistic <= 0.0:
        return DependenceTest(0.0, 1.0, block)
    rng = np.random.default_rng(seed)
    blocks = n // block + 2
    exceed = 0
    done = 0
    while done < replicates:
        count = min(CHUNK, replicates - done)
        flipped = np.empty((count, n))
        for row in range(count):
            # Blocks of random sign, their boundaries shifted by a random offset.
            offset = int(rng.integers(0, block))
            signs = np.repeat(rng.choice(np.array([-1.0, 1.0]), size=blocks), block)
            flipped[row] = e * signs[offset:offset + n]
        moment = np.asarray(operator @ flipped.T)
        exceed += int(np.count_nonzero(ratio(moment, np.sum(flipped ** 2, axis=1))
                                       >= statistic))
        done += count
    return DependenceTest(statistic, (1.0 + exceed) / (1.0 + replicates), block)

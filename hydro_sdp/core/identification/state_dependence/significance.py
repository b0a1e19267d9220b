"""
Whether a parameter's dependence on a state is significant, with autocorrelated residuals.

The reasoning is in docs/methods.md section 14.5.

"""

from __future__ import annotations

from dataclasses import dataclass
import math

from hydro_sdp.core.arrays import FloatArray, IntArray
from hydro_sdp.core.identification.state_dependence.banded import (
    banded_factor, banded_solve, null_basis, penalty_bands)
from hydro_sdp.core.identification.state_dependence.nvr import nvr_range
from hydro_sdp.core.identification.state_dependence.ordering import coarsened, Ordering
from hydro_sdp.core.identification.state_dependence.random_walk import GroupStats, inner, order_of
import numpy as np
from scipy import sparse
from scipy.linalg import LinAlgError
from scipy.special import betaincinv

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
#: Largest share of the groups' degrees of freedom the test's walks may take: a dependence
#: is a curve smoother than the groups (a held command is one group, one run).
SMOOTH_SHARE = 0.25
#: The replicates are extended to ``MORE`` times as many (less one: 199 to 999) when the
#: first ones leave the decision open.
MORE = 5


def _centred(series: FloatArray) -> tuple[int, int, FloatArray, float]:
    """Return the series' length, its longest block, the series centred and its power."""
    values = np.asarray(series, dtype=np.float64)
    n = values.size
    centred = values - np.mean(values) if n else values
    return n, max(1, n // MIN_BLOCKS), centred, inner(centred, centred)


def _autocovariance(centred: FloatArray, lags: int) -> FloatArray:
    """Return the sums of lagged products of a centred series, lags 0 to ``lags - 1``."""
    size = 1 << int(math.ceil(math.log2(2 * centred.size)))
    spectrum = np.fft.rfft(centred, size)
    return np.fft.irfft(spectrum * np.conj(spectrum), size)[:lags]


def automatic_block(series: FloatArray) -> int:
    """
    Return the block length of the dependence test: Politis and White's rule, samples.

    The reasoning is in docs/methods.md section 14.5.

    ``series``: residuals in time order.
    Returns: samples per block (>= 1).
    """
    n, longest, centred, power = _centred(series)
    if n < 4 * MIN_BLOCKS or power <= 0.0:
        return longest
    run = max(5, math.ceil(math.sqrt(math.log10(n))))
    widest = math.ceil(math.sqrt(n)) + run
    covariance = _autocovariance(centred, min(n, widest + run + 1)) / n
    standing = np.abs(covariance[1:] / covariance[0]) >= 2.0 * math.sqrt(math.log10(n) / n)
    # The first lag m after which `run` lags in a row stand below the bound.
    window = np.asarray(np.lib.stride_tricks.sliding_window_view(standing, run).any(axis=1))
    quiet = np.flatnonzero(~window[:widest])
    lags = min(2 * max(int(quiet[0]) if quiet.size else widest, 1), widest)
    k = np.arange(1, lags + 1)
    flat_top = np.minimum(1.0, 2.0 * (1.0 - k / lags))
    first = 2.0 * float(np.sum(flat_top * k * covariance[1:lags + 1]))
    zero = float(covariance[0] + 2.0 * np.sum(flat_top * covariance[1:lags + 1]))
    if not zero > 0.0:
        return longest
    optimal = (2.0 * first ** 2 / (4.0 / 3.0 * zero ** 2) * n) ** (1.0 / 3.0)
    return int(min(longest, max(1, math.ceil(optimal))))


def block_length(series: FloatArray) -> int:
    """
    Return the block length for a residual series, samples.

    ``series``: residuals in time order.
    Returns: samples per block (>= 1).
    """
    n, longest, centred, power = _centred(series)
    if n < 4 or power <= 0.0:
        return min(longest, max(1, int(round(n ** (1.0 / 3.0)))))
    acf = _autocovariance(centred, n) / power
    below = np.flatnonzero(acf[1:longest + 1] < ACF_CUT)
    lag = int(below[0]) + 1 if below.size else longest
    return int(min(longest, max(math.ceil(n ** (1.0 / 3.0)), 2 * lag)))


def smooth_limit(weight: float, groups: int, kind: str) -> float:
    """Return the largest NVR the test scans: a walk of :data:`SMOOTH_SHARE` of the groups' dof."""
    d = order_of(kind)
    eigen = (2.0 * np.sin(np.pi * np.arange(groups) / (2.0 * groups))) ** (2 * d)
    target = max(2.0, SMOOTH_SHARE * groups)
    low, high = -30.0, 30.0
    for _ in range(60):
        middle = 0.5 * (low + high)
        dof = float(np.sum(1.0 / (1.0 + eigen / math.exp(middle))))
        low, high = (middle, high) if dof < target else (low, middle)
    return math.exp(low) / weight


class LikelihoodRatio:
    """
    The likelihood ratio of a walk against a flat parameter, for many series at once.

    ``weight``: ``sum x^2`` per group.
    """

    def __init__(self, weight: FloatArray, count: int, kind: str) -> None:
        self.weight = np.asarray(weight, dtype=np.float64)
        self.count = count
        self.kind = kind
        self.d = order_of(kind)
        groups = self.weight.size
        stats = GroupStats(self.weight, np.zeros(groups), 0.0, count)
        low, high = nvr_range(stats)
        high = min(high, smooth_limit(stats.scale, groups, kind))
        self.factors: list[tuple[float, FloatArray, float]] = []
        penalty = penalty_bands(groups, kind)
        for nvr in np.geomspace(low, max(high, low), TEST_SCAN):
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

        ``moment``: ``sum x z`` per group, shape ``(M, series)``.
        Returns: ``max(0, -2 log L(flat) - min over the scan of -2 log L(nvr))`` per series.
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

    Attributes
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
    replicates: int = 0


def dependence_test(residual: FloatArray, x: FloatArray, state: FloatArray,
                    ordering: Ordering, kind: str, *, replicates: int = 199,
                    seed: int = 0, runs: IntArray | None = None,
                    alpha: float = 0.01) -> DependenceTest:
    """
    Test whether the parameter of ``z = x p(state) + e`` depends on the state.

    ``residual``: the term's partial residual at every sample, less the parameter held constant
    (the null's residuals and the data, methods 14.5).
    ``x``: the term's regressor at every sample.
    ``state``: the state at every sample.
    ``ordering``: the term's groups (its samples, ascending, are the time order); pooled to
    :data:`TEST_GROUPS`.
    ``replicates``: bootstrap replicates; ``MORE`` times as many (less one) when they leave the
    decision ``p <= alpha`` open.
    ``runs``: run of every sample (a command held, within one record): blocks are cut only where
    the run changes; None: anywhere.
    Returns: the ratio, its p-value, the block length and the replicates drawn.
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
    e = np.asarray(residual, dtype=np.float64)[samples]
    statistic = float(ratio(np.asarray(operator @ e)[:, None], np.array([inner(e, e)]))[0])
    block = automatic_block(e)
    if statistic <= 0.0:
        return DependenceTest(0.0, 1.0, block)
    if runs is None:
        cuts = np.arange(n)
    else:
        labels = np.asarray(runs)[samples]
        cuts = np.flatnonzero(np.r_[True, labels[1:] != labels[:-1]])
    restored = _restored(e, xs, _starts(cuts, n, block, 0))
    rng = np.random.default_rng(seed)
    draws: list[FloatArray] = []
    goal, done = replicates, 0
    while done < goal:
        count = min(CHUNK, goal - done)
        flipped = np.empty((count, n))
        for row in range(count):
            flipped[row] = restored * _block_signs(cuts, n, block, rng)
        draws.append(ratio(np.asarray(operator @ flipped.T), np.sum(flipped ** 2, axis=1)))
        done += count
        if done == goal and goal < MORE * replicates + MORE - 1 and _undecided(
                statistic, np.concatenate(draws), alpha):
            goal = MORE * replicates + MORE - 1
    exceed = int(np.count_nonzero(np.concatenate(draws) >= statistic))
    return DependenceTest(statistic, (1.0 + exceed) / (1.0 + done), block, done)


def _undecided(statistic: float, draws: FloatArray, alpha: float) -> bool:
    """Whether more replicates could bring a p-value above ``alpha`` to it."""
    count = draws.size
    exceed = int(np.count_nonzero(draws >= statistic))
    if (1.0 + exceed) / (1.0 + count) <= alpha:
        return False
    return exceed == 0 or float(betaincinv(exceed, count - exceed + 1, 0.005)) < alpha


def _starts(cuts: IntArray, n: int, block: int, phase: int) -> IntArray:
    """Return where blocks about ``block`` long start, at ``cuts`` only, from ``phase``."""
    # Every `block` samples from the phase, moved on to the next place a cut may go.
    wanted = np.arange(phase, n, block)
    starts = cuts[np.minimum(np.searchsorted(cuts, wanted), cuts.size - 1)]
    return np.unique(np.r_[0, starts])


def _block_signs(cuts: IntArray, n: int, block: int, rng: np.random.Generator) -> FloatArray:
    """Return a random sign per block: blocks about ``block`` long, cut at ``cuts`` only."""
    starts = _starts(cuts, n, block, int(rng.integers(0, block)))
    signs = rng.choice(np.array([-1.0, 1.0]), size=starts.size)
    return np.repeat(signs, np.diff(np.r_[starts, n]))


def _restored(e: FloatArray, x: FloatArray, starts: IntArray) -> FloatArray:
    """
    Return the null's residuals with each block's own level scaled by ``1 / sqrt(1 - h)``.

    The reasoning is in docs/methods.md section 14.5.
    """
    block = np.repeat(np.arange(starts.size), np.diff(np.r_[starts, e.size]))
    weight = np.bincount(block, weights=x * x, minlength=starts.size)
    level = np.bincount(block, weights=x * e, minlength=starts.size) / np.maximum(weight,
                                                                                  1e-300)
    leverage = weight / max(float(np.sum(weight)), 1e-300)
    scale = 1.0 / np.sqrt(np.maximum(1.0 - leverage, 0.5)) - 1.0
    return e + x * (level * scale)[block]

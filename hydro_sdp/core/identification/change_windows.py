"""Dead time and first-order valve lag of a joint, identified together (methods 1.5)."""

from __future__ import annotations

import copy
import math
from typing import Sequence

from hydro_sdp.core.arrays import FloatArray, IntArray
from hydro_sdp.core.errors import DataError
from hydro_sdp.core.identification.experiment import Experiment
from hydro_sdp.core.model.first_order import first_order
from hydro_sdp.core.model.timing import delayed_at, SamplePeriod
import numpy as np
import numpy.typing as npt
from scipy.optimize import minimize_scalar

#: Candidate lag time constants, in sample periods (0: pure delay).
LAG_GRID = (0.0, 1.0, 1.5, 2.0, 3.0, 4.0, 5.0, 6.0, 8.0, 10.0, 12.0, 15.0, 20.0, 25.0, 30.0)
#: A lag is kept only when it lowers the residual of the best pure delay by this share.
LAG_GAIN = 0.02
#: Samples of the old command scored before the earliest place a change can show.
BEFORE = 30
#: Samples of the new command scored after the latest (five times the grid's longest lag).
AFTER = 150
#: Parameters of each window: old level, new level, its drift, free initial speed.
_PER_WINDOW = 4


def lag_pole(time_constant: float, dt: SamplePeriod) -> float:
    """Return ``p = exp(-dt / T)`` (0 for no lag)."""
    return math.exp(-dt / time_constant) if time_constant > 0.0 else 0.0


class ChangeWindows:
    """
    The measured increments around every change of the command.

    ``max_delay``: largest dead time, samples.
    """

    def __init__(self, experiments: Sequence[Experiment], max_delay: int) -> None:
        increments, firsts, lengths, earliest = [], [], [], []
        offset = 0
        self.max_delay = max_delay
        # Where each experiment's windows lie, by the experiment's id; the experiments are
        # held, so that no other object takes one of these ids while the windows live.
        self._experiments = tuple(experiments)
        self._spans: dict[int, tuple[int, int]] = {}
        count = 0
        for experiment in experiments:
            n = experiment.y.size - experiment.start - 1
            self._spans[id(experiment)] = (count, count)
            # The command change at v[m] shows in increment m - start - 1 + delay.
            shows = np.flatnonzero(experiment.v[1:] != experiment.v[:-1]) - experiment.start
            increments.append(np.diff(experiment.y[experiment.start:]))
            offset += n
            if shows.size == 0:
                continue
            previous = np.r_[-np.inf, shows[:-1]]
            following = np.r_[shows[1:], np.inf]
            first = np.maximum.reduce([shows + 1 - BEFORE, previous + max_delay + 1,
                                       np.zeros(shows.size)])
            last = np.minimum.reduce([shows + 1 + max_delay + AFTER, following + 1,
                                      np.full(shows.size, n)])
            keep = (last > first) & (shows + max_delay >= 0) & (shows + 1 < n)
            self._spans[id(experiment)] = (count, count + int(np.count_nonzero(keep)))
            count += int(np.count_nonzero(keep))
            firsts.append(offset - n + first[keep].astype(np.int64))
            lengths.append((last - first)[keep].astype(np.int64))
            earliest.append((shows + 1 - first)[keep].astype(np.int64))
        dy = np.concatenate(increments) if increments else np.zeros(0)
        at = np.concatenate(firsts) if firsts else np.zeros(0, np.int64)
        #: Samples in each window.
        self.length: IntArray = np.concatenate(lengths) if lengths else at
        #: Where in its window each change shows with a dead time of one sample.
        self.earliest: IntArray = np.concatenate(earliest) if earliest else at
        width = int(self.length.max()) if at.size else 0
        t = np.arange(width)
        mask = t < self.length[:, None]
        gathered = dy[np.clip(at[:, None] + t, 0, max(dy.size - 1, 0))] if dy.size else 0.0
        #: Increments of each window from its first sample, 0 past its end.
        self.dy: FloatArray = np.where(mask, gathered, 0.0)
        self.windows = int(at.size)
        self.energy = float(np.sum(self.dy ** 2))
        # Windows share a few places of the change, and a dead time moves them all alike.
        self._places, self._place_of = np.unique(self.earliest, return_inverse=True)
        self._by_delay: dict[int, tuple[npt.NDArray[np.bool_], FloatArray, FloatArray]] = {}
        # Per (dead time, pole), each window's share of the explained energy; and the
        # windows these are, of those of the windows that compute them.
        self._shares: dict[tuple[int, float], FloatArray] = {}
        self._source = self
        self._rows: IntArray | None = None

    def part(self, experiments: Sequence[Experiment], max_delay: int | None = None
             ) -> ChangeWindows:
        """
        Return the windows of some of the experiments, scored from what these compute.

        ``experiments``: experiments these windows were made of, in any order (any other: the
        windows are made anew).
        ``max_delay``: largest dead time, samples (another than these windows': made anew).
        """
        if max_delay is not None and max_delay != self.max_delay:
            return ChangeWindows(experiments, max_delay)
        spans = [self._source._spans.get(id(e)) for e in experiments]
        if any(span is None for span in spans):
            return ChangeWindows(experiments, self.max_delay)
        rows = np.concatenate([np.arange(*span) for span in spans if span is not None]
                              + [np.zeros(0, np.int64)])
        part = copy.copy(self._source)
        part.length, part.earliest = part.length[rows], part.earliest[rows]
        width = int(part.length.max()) if rows.size else 0
        # The increments exactly as made for these experiments alone (their energy too).
        part.dy = part.dy[rows, :width] if rows.size else np.zeros((0, 0))
        part.windows = int(rows.size)
        part.energy = float(np.sum(part.dy ** 2))
        part._rows = rows
        return part

    def residual(self, delay: int, pole: float) -> float:
        """
        Residual sum of squares with dead time ``delay`` and lag pole ``pole``.

        ``delay``: dead time, samples.
        ``pole``: lag pole ``p`` (0: pure delay).
        Returns: sum over the windows of the squared residuals, degrees squared.
        """
        if self.windows == 0:
            return 0.0
        shares = self._source._explained(delay, float(pole))
        if self._rows is not None:
            shares = shares[self._rows]
        return max(self.energy - float(np.sum(shares)), 0.0)

    def angle_error(self, delay: int, pole: float) -> tuple[float, int]:
        """
        Return the summed absolute angle error over the windows, and the samples summed.

        ``delay``: dead time, samples.
        ``pole``: lag pole ``p`` (0: pure delay).
        Returns: degrees summed over the samples, and their number.
        """
        if self.windows == 0:
            return 0.0, 0
        sums = self._source._angle_sums(delay, float(pole))
        if self._rows is not None:
            sums = sums[self._rows]
        return float(np.sum(sums)), int(np.sum(self.length))

    def _angle_sums(self, delay: int, p: float) -> FloatArray:
        """Return each window's summed absolute angle error with this timing."""
        key = (delay, -1.0 - p)
        sums = self._shares.get(key)
        if sums is None:
            basis, theta = self._solve(delay, p)
            predicted = np.einsum('wtj,wj->wt', basis[self._place_of], theta)
            mask = np.arange(self.dy.shape[1])[None, :] < self.length[:, None]
            error = np.cumsum(np.where(mask, self.dy - predicted, 0.0), axis=1)
            sums = np.sum(np.abs(error) * mask, axis=1)
            self._shares[key] = sums
        return sums

    def _explained(self, delay: int, p: float) -> FloatArray:
        """Return each window's fitted parameters times their right-hand sides."""
        shares = self._shares.get((delay, p))
        if shares is None:
            shares = self._fit(delay, p)
            self._shares[(delay, p)] = shares
        return shares

    def _fit(self, delay: int, p: float) -> FloatArray:
        """Fit every window with dead time ``delay`` and lag pole ``p``."""
        basis, theta = self._solve(delay, p)
        rhs = np.einsum('wt,wtj->wj', self.dy, basis[self._place_of])
        return np.asarray(theta * rhs, dtype=np.float64)

    def _solve(self, delay: int, p: float) -> tuple[FloatArray, FloatArray]:
        """Return the basis per place of the change and every window's fitted parameters."""
        width = self.dy.shape[1]
        t = np.arange(width, dtype=np.float64)
        after, exponent, drift = self._shifted(delay)
        # The old level, filtered and continued past the change, and the free initial
        # speed decaying from the window's first sample span the same responses as
        # {1 then p^(i+1)} and {p^(t+1)}.
        decay = np.where(after, p ** exponent, 1.0) if p > 0.0 else \
            (~after).astype(np.float64)
        step = np.where(after, 1.0 - decay, 0.0)
        ramp = first_order(drift, p, 1.0 - p) if p > 0.0 else drift
        free = np.broadcast_to(p ** (t + 1.0) if p > 0.0 else np.zeros(width), after.shape)
        basis = np.stack([decay, step, ramp, free], axis=2)
        rhs = np.einsum('wt,wtj->wj', self.dy, basis[self._place_of])
        # Each window's Gram matrix: partial sums from its first sample to its last, of
        # the products of the columns on and above the diagonal (the rest mirror them).
        upper, lower = np.triu_indices(_PER_WINDOW)
        grams = np.cumsum(basis[:, :, upper] * basis[:, :, lower], axis=1)
        gram = np.empty((self.windows, _PER_WINDOW, _PER_WINDOW))
        gram[:, upper, lower] = gram[:, lower, upper] = grams[self._place_of, self.length - 1]
        # Unit diagonal, then a tiny ridge: columns may vanish (no lag) or coincide
        # (a change at the window's first sample).
        diagonal = np.einsum('wjj->wj', gram)
        norm = np.where(diagonal > 0.0, 1.0 / np.sqrt(np.where(diagonal > 0.0, diagonal, 1.0)),
                        0.0)
        gram = gram * norm[:, :, None] * norm[:, None, :] + 1e-10 * np.eye(_PER_WINDOW)
        theta = np.linalg.solve(gram, (rhs * norm)[:, :, None])[:, :, 0]
        return basis, np.asarray(theta * norm, dtype=np.float64)

    def _shifted(self, delay: int) -> tuple[npt.NDArray[np.bool_], FloatArray, FloatArray]:
        """Per place of the change with dead time ``delay``: samples after it, ``i + 1``, drift."""
        cached = self._by_delay.get(delay)
        if cached is None:
            t = np.arange(self.dy.shape[1], dtype=np.float64)
            i = t[None, :] - (self._places + (delay - 1))[:, None]
            after = i >= 0.0
            cached = (after, np.maximum(i + 1.0, 0.0), np.where(after, i / AFTER, 0.0))
            self._by_delay[delay] = cached
        return cached


# The paper baseline's delay (:mod:`.paper_baseline`): one mean speed with a drift
# per stretch of the delayed command, the lag inverted in the increments.


def _rows(experiments: Sequence[Experiment], delay: int, window: int
          ) -> tuple[FloatArray, np.ndarray, np.ndarray, FloatArray, int]:
    """Increments, stretch indices and time within the stretch, one padded row each."""
    width = max(e.y.size - e.start - 1 for e in experiments)
    dy = np.zeros((len(experiments), width))
    group = np.zeros((len(experiments), width), dtype=np.int64)
    mask = np.zeros((len(experiments), width), dtype=bool)
    time = np.zeros((len(experiments), width))
    offset = 0
    for row, experiment in enumerate(experiments):
        k = np.arange(experiment.start + 1, experiment.y.size)
        delayed = delayed_at(experiment.v, k, delay)
        # One group per stretch of one delayed command, its first `window` samples.
        changed = np.r_[True, delayed[1:] != delayed[:-1]]
        stretch = np.cumsum(changed) - 1
        since = np.arange(k.size) - np.flatnonzero(changed)[stretch]
        dy[row, :k.size] = experiment.y[k] - experiment.y[k - 1]
        group[row, :k.size] = stretch + offset
        time[row, :k.size] = since
        mask[row, :k.size] = since < window
        offset += int(stretch[-1]) + 1 if stretch.size else 0
    return dy, group, mask, time, offset


def lagged_residual(experiments: Sequence[Experiment], delay: int, pole: float) -> float:
    """Squared error of the increments explained by lagged per-level mean speeds."""
    return _residual(*_rows(experiments, delay, 2 * delay + 50), pole)


def _residual(dy: FloatArray, group: np.ndarray, mask: np.ndarray, time: FloatArray,
              groups: int, pole: float) -> float:
    raw: FloatArray = dy
    if pole > 0.0:
        previous = np.concatenate([dy[:, :1], dy[:, :-1]], axis=1)
        raw = np.asarray((dy - pole * previous) / (1.0 - pole), dtype=np.float64)
    # Each stretch: a mean speed with a linear drift over its first samples (the speed
    # changes along the stroke; a lag or a delay shows where the command changes).
    g, t, r = group[mask], time[mask], raw[mask]
    n = np.bincount(g, minlength=groups).astype(np.float64)
    st = np.bincount(g, weights=t, minlength=groups)
    stt = np.bincount(g, weights=t * t, minlength=groups)
    sr = np.bincount(g, weights=r, minlength=groups)
    srt = np.bincount(g, weights=r * t, minlength=groups)
    denominator = n * stt - st * st
    safe = np.where(denominator > 0.0, denominator, 1.0)
    slope = np.where(denominator > 0.0, (n * srt - st * sr) / safe, 0.0)
    intercept = (sr - slope * st) / np.maximum(n, 1.0)
    predicted = np.where(mask, intercept[group] + slope[group] * time, 0.0)
    if pole > 0.0:
        predicted = first_order(predicted, pole, 1.0 - pole, predicted[:, 0])
    return float(np.sum(((dy - predicted) * mask) ** 2))


def fit_delay_lag_and_pure(experiments: Sequence[Experiment], dt: SamplePeriod, max_delay: int,
                           windows: ChangeWindows | None = None
                           ) -> tuple[int, float, FloatArray, int]:
    """
    Dead time and lag time constant that explain the increments best, and the best pure delay.

    ``experiments``: experiments with at least ``max_delay`` samples of command history.
    ``dt``: sample period, s.
    ``max_delay``: largest dead time, samples.
    ``windows``: the experiments' windows, if made already (:meth:`ChangeWindows.part`).
    Returns: ``(delay, time_constant, explained, pure)``: dead time (samples), lag time constant
    (s, 0 for none), per candidate delay 1..max_delay the share of the windows' squared increments
    explained with the best lag tried there, and the dead time that explains them best without a
    lag (what stands when the lag does not earn its place on held-out experiments).
    Raises DataError if no command change can show in the experiments.
    """
    if windows is None:
        windows = ChangeWindows(experiments, max_delay)
    if windows.windows == 0:
        # Without a change every pair would explain everything: say so instead.
        raise DataError('the command never changes in a way the delay could show in '
                        f'(changes at least {max_delay} samples apart are needed)')
    best = {delay: (windows.residual(delay, 0.0), 0.0) for delay in range(1, max_delay + 1)}
    pure_score, pure = min((score, delay) for delay, (score, _) in best.items())
    # A lag of T samples moves the best pure delay later by less than T (0.3-0.4 T on
    # J2 steps): the dead time with the lag lies between T + 3 samples below it and 2 above.
    for factor in LAG_GRID[1:]:
        pole = lag_pole(factor * dt, dt)
        for delay in range(max(1, pure - math.ceil(factor) - 3), min(pure + 2, max_delay) + 1):
            best[delay] = min(best[delay], (windows.residual(delay, pole), factor * dt))
    score, delay, lag = min((score, delay, lag) for delay, (score, lag) in best.items())
    if lag > 0.0:
        # Between the neighbours of the best time constant of the grid, on the best dead
        # time and the ones beside it (the two trade a little at the grid's steps).
        index = LAG_GRID.index(round(lag / dt, 9))
        low = LAG_GRID[max(index - 1, 1)] * dt
        high = LAG_GRID[min(index + 1, len(LAG_GRID) - 1)] * dt
        for near in range(max(1, delay - 1), min(max_delay, delay + 1) + 1):
            result = minimize_scalar(
                lambda x, d=near: windows.residual(d, lag_pole(math.exp(x), dt)),
                bounds=(math.log(low), math.log(high)), method='bounded',
                options={'xatol': 0.01})
            if float(result.fun) < best[near][0]:
                best[near] = (float(result.fun), math.exp(float(result.x)))
        score, delay, lag = min((score, delay, lag) for delay, (score, lag) in best.items())
    energy = windows.energy if windows.energy > 0.0 else 1.0
    explained = np.array([1.0 - best[d][0] / energy for d in sorted(best)])
    if lag > 0.0 and score < (1.0 - LAG_GAIN) * pure_score:
        return delay, lag, explained, pure
    return pure, 0.0, explained, pure

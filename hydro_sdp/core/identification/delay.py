"""Dead time (and valve lag) of a hydraulic joint, estimated three ways (methods 1.5)."""

from __future__ import annotations

from dataclasses import dataclass, replace
import math
from typing import Sequence

from hydro_sdp.core.arrays import FloatArray
from hydro_sdp.core.errors import DataError
from hydro_sdp.core.identification.change_windows import (
    ChangeWindows, fit_delay_lag_and_pure, lag_pole)
from hydro_sdp.core.identification.experiment import Experiment
from hydro_sdp.core.model.first_order import first_order
from hydro_sdp.core.model.sample_period import whole_samples_seconds
from hydro_sdp.core.model.timing import delayed_at, SamplePeriod
import numpy as np


@dataclass(frozen=True)
class DelayEstimate:
    """
    The delay, and what each estimator found.

    Attributes
    ----------
    samples : int
        Chosen delay, samples (from the fit).
    seconds : float
        The same in seconds.
    onset : int or None
        Delay from motion onsets of the fastest steps (None without steps).
    explained : FloatArray
        Share of the squared increments around the command changes explained at each candidate
        delay 1..max_delay, with the best lag tried there.
    lag : float
        First-order valve lag time constant found with the delay, s (0: none).
    pure : int or None
        Dead time that explains the increments best without a lag (None: ``fit``).
    fitted_lag : float
        The lag the increments showed, kept or not, s: how long the valve's transient lasts.

    """

    samples: int
    seconds: float
    fit: int
    onset: int | None
    xcorr: int | None
    explained: FloatArray
    lag: float = 0.0
    pure: int | None = None
    fitted_lag: float = 0.0

    @property
    def transient(self) -> float:
        """Return how long after a command change the valve's transient lasts, s (5 lags)."""
        return 5.0 * max(self.lag, self.fitted_lag)

    def without_lag(self, dt: SamplePeriod) -> DelayEstimate:
        """Return the estimate with the best pure delay and no lag."""
        pure = self.fit if self.pure is None else self.pure
        return replace(self, samples=pure, seconds=whole_samples_seconds(pure, dt), fit=pure,
                       lag=0.0)

    @property
    def agree(self) -> bool:
        """Whether the other estimators are within one sample of the fit."""
        others = [d for d in (self.onset, self.xcorr) if d is not None]
        return all(abs(d - self.fit) <= 1 for d in others)


def _onset(experiments: Sequence[Experiment], noise: float, max_delay: int,
           pole: float) -> int | None:
    # Samples the lag needs to reach half of a step in speed (0 without lag).
    rise = math.ceil(math.log(0.5) / math.log(pole)) - 1 if pole > 0.0 else 0
    found = []
    for experiment in experiments:
        if experiment.kind != 'step':
            continue
        start = experiment.start
        held = np.flatnonzero(experiment.v[start + 1:] != experiment.level)
        length = int(held[0]) if held.size else experiment.v.size - start - 1
        window = experiment.y[start:start + 1 + min(length, experiment.y.size)]
        if window.size < max_delay + 20:
            continue
        # Speed over five samples centred on each one: a step in speed reaches half
        # height exactly where it happens.
        speed = np.r_[np.full(2, 0.0), (window[5:] - window[:-5]) / 5.0, np.full(2, 0.0)]
        final = float(np.median(speed[speed.size // 2:]))
        if abs(final) < 20.0 * max(noise, 1e-9) / 5.0:
            continue
        above = np.sign(final) * speed >= 0.5 * abs(final)
        sustained = above[:-3] & above[1:-2] & above[2:-1] & above[3:]
        crossing = np.flatnonzero(sustained)
        if crossing.size == 0:
            continue
        # speed[j] is centred on the increment y[start + j] - y[start + j - 1], j >= 1:
        # the first command v[start + 1] shows first in increment 1 + delay.
        found.append((abs(final), int(crossing[0]) + 1 - 1 - rise))
    if len(found) < 2:
        return None
    found.sort(reverse=True)
    fastest = [onset for _, onset in found[:max(2, len(found) // 3)]]
    return int(round(float(np.median(fastest))))


def _xcorr(experiments: Sequence[Experiment], max_delay: int, pole: float) -> int | None:
    score = np.zeros(max_delay + 1)
    for experiment in experiments:
        acceleration = np.diff(experiment.y, 2)
        change = np.diff(experiment.v)[:-1]
        if acceleration.size <= max_delay or not np.any(change):
            continue
        if pole > 0.0:
            # Through the lag a change of command changes the speed over the samples
            # after the dead time: correlate with that shape, not with a spike.
            change = first_order(change, pole, 1.0 - pole)
        for lag in range(1, max_delay + 1):
            score[lag] += float(np.dot(acceleration[lag:], change[:change.size - lag]))
    if not np.any(score):
        return None
    # A command change between v[i] and v[i+1] changes the speed in y[i+1+delay]: the
    # second difference centred one sample earlier, so the lag is delay - 1.
    return int(np.argmax(score)) + 1


def estimate_delay(experiments: Sequence[Experiment], dt: SamplePeriod, *, max_delay: int,
                   rest: float = 0.0, noise: float = 0.0,
                   windows: ChangeWindows | None = None) -> DelayEstimate:
    """Estimate the pure delay from experiments."""
    if not experiments:
        raise DataError('no experiments to estimate the delay from')
    shared = None if windows is None else windows.part(experiments, max_delay)
    best, lag, explained, pure = fit_delay_lag_and_pure(experiments, dt, max_delay, shared)
    return DelayEstimate(samples=best, seconds=whole_samples_seconds(best, dt), fit=best,
                         onset=_onset(experiments, noise, max_delay, lag_pole(lag, dt)),
                         xcorr=_xcorr(experiments, max_delay, lag_pole(lag, dt)),
                         explained=explained, lag=lag, pure=pure, fitted_lag=lag)


@dataclass(frozen=True)
class LevelSpeed:
    """
    Mean speed of the joint while one command level acted on it.

    Attributes
    ----------
    level : float
        Command, input units.
    speed : float
        Mean angular velocity, deg/s.
    standard_error : float
        Its standard error, deg/s.
    gain : float
        The SDP gain ``b_tau = speed dt / (level - rest)``, deg per sample per unit (NaN at rest).

    """

    level: float
    speed: float
    standard_error: float
    samples: int
    gain: float


def level_speeds(experiments: Sequence[Experiment], delay: int, dt: SamplePeriod, *,
                 rest: float = 0.0, skip: int = 0, min_samples: int = 5) -> list[LevelSpeed]:
    """
    Mean speed per experiment and delayed command level (the points of Figs. 2 and 3).

    The reasoning is in docs/methods.md section 1.10.

    ``dt``: sample period, s.
    ``min_samples``: fewest samples for a point.
    Returns: one point per experiment and level, sorted by level.
    """
    points = []
    for experiment in experiments:
        k = np.arange(experiment.start + 1, experiment.y.size)
        delayed = delayed_at(experiment.v, k, delay)
        dy = experiment.y[k] - experiment.y[k - 1]
        changed = np.r_[True, delayed[1:] != delayed[:-1]]
        since_change = np.arange(k.size) - np.maximum.accumulate(
            np.where(changed, np.arange(k.size), 0))
        keep = since_change >= skip
        for level in np.unique(delayed[keep]):
            values = dy[keep & (delayed == level)]
            if values.size < min_samples:
                continue
            mean = float(np.mean(values))
            error = float(np.std(values, ddof=1) / np.sqrt(values.size))
            gain = mean / (level - rest) if level != rest else float('nan')
            points.append(LevelSpeed(float(level), mean / dt, error / dt, int(values.size),
                                     gain))
    return sorted(points, key=lambda p: p.level)

"""
Dead time and first-order valve lag of a joint, identified together.

A real valve answers a step with a dead time (electronics, pilot stage) and
then a rise (the spool's travel): ``w_k = p w_{k-1} + (1 - p) rate(v_{k-tau})``
with ``p = exp(-dt / T)``, the model's ``valve_lag`` effect. With the lag
known, the speed the map gives is recovered from the measured increments by
inverting the lag, ``r_k = (dy_k - p dy_{k-1}) / (1 - p)``; its mean per
experiment and delayed command level is a map free of any shape, and the
pair ``(tau, T)`` whose lagged means explain the measured increments best wins
(the differenced-output fit of docs/methods.md section 1.5, with the lag).

"""

from __future__ import annotations

import math
from typing import Sequence

from hydro_sdp.core.arrays import FloatArray
from hydro_sdp.core.experiments import Experiment
from hydro_sdp.core.timing import delayed_at
import numpy as np
from scipy.signal import lfilter

#: Candidate lag time constants, in sample periods (0: pure delay).
LAG_GRID = (0.0, 1.0, 1.5, 2.0, 3.0, 4.0, 5.0, 6.0, 8.0, 10.0, 12.0, 15.0, 20.0, 25.0, 30.0)
#: A lag is kept only when it lowers the residual of the best pure delay by this share.
LAG_GAIN = 0.02


def lag_pole(time_constant: float, dt: float) -> float:
    """Return ``p = exp(-dt / T)`` (0 for no lag)."""
    return math.exp(-dt / time_constant) if time_constant > 0.0 else 0.0


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
    """
    Squared error of the increments explained by lagged per-level mean speeds.

    Parameters
    ----------
    experiments : sequence of Experiment
        The experiments.
    delay : int
        Dead time, samples.
    pole : float
        Lag pole ``p`` (0: pure delay).

    Returns
    -------
    float
        Sum of squared residuals of the increments, degrees squared.

    """
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
        predicted, _ = lfilter([1.0 - pole], [1.0, -pole], predicted, axis=1,
                               zi=pole * predicted[:, :1])
    return float(np.sum(((dy - predicted) * mask) ** 2))


def fit_delay_and_lag(experiments: Sequence[Experiment], dt: float, max_delay: int
                      ) -> tuple[int, float, FloatArray]:
    """
    Dead time and lag time constant that explain the increments best.

    Parameters
    ----------
    experiments : sequence of Experiment
        Experiments with at least ``max_delay`` samples of command history.
    dt : float
        Sample period, s.
    max_delay : int
        Largest dead time, samples.

    Returns
    -------
    tuple
        ``(delay, time_constant, explained)``: dead time (samples), lag time
        constant (s, 0 for none) and, per candidate delay 1..max_delay, the share
        of the increments' variance explained with the best lag tried there.

    """
    total = sum(float(np.sum(np.diff(e.y[e.start:]) ** 2)) for e in experiments)
    window = 2 * max_delay + 50
    rows = {delay: _rows(experiments, delay, window) for delay in range(1, max_delay + 1)}
    pure = {delay: _residual(*rows[delay], 0.0) for delay in rows}
    best_pure = min((score, delay) for delay, score in pure.items())
    # A lag of T samples looks like about T samples of extra delay: with it, the dead
    # time lies that much below the best pure delay.
    best_lag = (math.inf, 1, 0.0)
    explained = np.array([1.0 - pure[d] / total if total > 0 else 0.0 for d in sorted(pure)])
    for factor in LAG_GRID[1:]:
        centre = best_pure[1] - int(round(factor))
        for delay in range(max(centre - 2, 1), min(centre + 3, max_delay + 1)):
            lagged = _residual(*rows[delay], lag_pole(factor * dt, dt))
            explained[delay - 1] = max(explained[delay - 1],
                                       1.0 - lagged / total if total > 0 else 0.0)
            best_lag = min(best_lag, (lagged, delay, factor))
    if best_lag[2] > 0.0 and best_lag[0] < (1.0 - LAG_GAIN) * best_pure[0]:
        return best_lag[1], best_lag[2] * dt, explained
    return best_pure[1], 0.0, explained

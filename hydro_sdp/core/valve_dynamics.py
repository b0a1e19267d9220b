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


def _rows(experiments: Sequence[Experiment], delay: int
          ) -> tuple[FloatArray, np.ndarray, np.ndarray, int]:
    """Increments and group indices of every experiment, one padded row each."""
    width = max(e.y.size - e.start - 1 for e in experiments)
    dy = np.zeros((len(experiments), width))
    group = np.zeros((len(experiments), width), dtype=np.int64)
    mask = np.zeros((len(experiments), width), dtype=bool)
    offset = 0
    for row, experiment in enumerate(experiments):
        k = np.arange(experiment.start + 1, experiment.y.size)
        _, inverse = np.unique(delayed_at(experiment.v, k, delay), return_inverse=True)
        dy[row, :k.size] = experiment.y[k] - experiment.y[k - 1]
        group[row, :k.size] = inverse + offset
        mask[row, :k.size] = True
        offset += int(inverse.max()) + 1 if inverse.size else 0
    return dy, group, mask, offset


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
    dy, group, mask, groups = _rows(experiments, delay)
    return _residual(dy, group, mask, groups, pole)


def _residual(dy: FloatArray, group: np.ndarray, mask: np.ndarray, groups: int,
              pole: float) -> float:
    if pole > 0.0:
        previous = np.concatenate([dy[:, :1], dy[:, :-1]], axis=1)
        raw = (dy - pole * previous) / (1.0 - pole)
    else:
        raw = dy
    counts = np.bincount(group[mask], minlength=groups)
    means = np.bincount(group[mask], weights=raw[mask], minlength=groups) / np.maximum(counts, 1)
    predicted = np.where(mask, means[group], 0.0)
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
        of the increments' variance explained with the best lag there.

    """
    total = sum(float(np.sum(np.diff(e.y[e.start:]) ** 2)) for e in experiments)
    best_pure = (math.inf, 1)
    best_lag = (math.inf, 1, 0.0)
    explained = np.zeros(max_delay)
    for delay in range(1, max_delay + 1):
        rows = _rows(experiments, delay)
        scores = [(_residual(*rows, lag_pole(factor * dt, dt)), factor) for factor in LAG_GRID]
        pure = scores[0][0]
        lagged, factor = min(scores)
        explained[delay - 1] = 1.0 - lagged / total if total > 0 else 0.0
        best_pure = min(best_pure, (pure, delay))
        best_lag = min(best_lag, (lagged, delay, factor))
    if best_lag[2] > 0.0 and best_lag[0] < (1.0 - LAG_GAIN) * best_pure[0]:
        return best_lag[1], best_lag[2] * dt, explained
    return best_pure[1], 0.0, explained

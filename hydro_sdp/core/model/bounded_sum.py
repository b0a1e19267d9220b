"""A cumulative sum clamped between two bounds: the end-stop recursion (methods 3.7)."""

from __future__ import annotations

import math

from hydro_sdp.core.arrays import FloatArray
import numpy as np

# Samples handled per reflection pass; bounds the cost of each switch between stops.
_CHUNK = 8192


def bounded_cumsum(x0: float, increments: FloatArray, low: float, high: float) -> FloatArray:
    """
    Solve ``x_k = min(max(x_{k-1} + d_k, low), high)`` for a whole sequence (methods 3.7).

    ``low``: lower bound (may be ``-inf``).
    ``high``: upper bound (may be ``inf``).
    """
    increments = np.asarray(increments, dtype=np.float64)
    n = increments.size
    x = min(max(float(x0), low), high)
    if math.isinf(low) and math.isinf(high):
        return np.r_[x, x + np.cumsum(increments)]
    starts = np.flatnonzero(np.diff(increments)) + 1
    if 8 * (starts.size + 1) > n:
        return _reflected_cumsum(x, increments, low, high)
    starts = np.r_[0, starts]
    lengths = np.diff(np.r_[starts, n])
    values = increments[starts]
    run_start = np.empty(starts.size)
    for i, (step, length) in enumerate(zip(values.tolist(), lengths.tolist())):
        run_start[i] = x
        x = min(max(x + step * length, low), high)
    steps_into_run = np.arange(1, n + 1) - np.repeat(starts, lengths)
    path = np.repeat(run_start, lengths) + np.repeat(values, lengths) * steps_into_run
    return np.r_[min(max(float(x0), low), high), np.clip(path, low, high)]


def _reflected_cumsum(x: float, increments: FloatArray, low: float, high: float) -> FloatArray:
    """Two-sided clamped cumulative sum by one-sided reflections, chunk by chunk."""
    n = increments.size
    out = np.empty(n + 1)
    out[0] = x
    reflect_high = True
    start = 0
    while start < n:
        stop = min(start + _CHUNK, n)
        path = x + np.cumsum(increments[start:stop])
        if reflect_high:
            path = _reflect(path, path - high, high, -1.0)
            crossed = np.flatnonzero(path < low)
        else:
            path = _reflect(path, low - path, low, 1.0)
            crossed = np.flatnonzero(path > high)
        if crossed.size:
            j = int(crossed[0])
            out[start + 1:start + 1 + j] = path[:j]
            x = low if reflect_high else high
            out[start + 1 + j] = x
            start += j + 1
            reflect_high = not reflect_high
        else:
            out[start + 1:stop + 1] = path
            x = float(path[-1])
            start = stop
    # Rounding in the reflection may step a hair past a bound.
    return np.clip(out, low, high, out=out)


def _reflect(path: FloatArray, excess: FloatArray, bound: float, sign: float) -> FloatArray:
    """Reflect ``path`` at ``bound`` given how far it overshoots it (``excess``)."""
    pushed = np.maximum.accumulate(excess)
    reflected = path + sign * np.maximum(pushed, 0.0)
    # Where the overshoot peaks the joint is at the stop; say so exactly, not up to rounding.
    reflected[(excess >= pushed) & (pushed > 0.0)] = bound
    return reflected

"""The pump's power cap of ``load_dependence``, fitted on the one-step increments (methods 8.2)."""

from __future__ import annotations

from hydro_sdp.core.arrays import FloatArray
from hydro_sdp.core.model.pump_and_load import power_allowed
import numpy as np
from scipy.optimize import least_squares

#: Fewest samples a direction needs for its cap to be fitted.
MIN_SAMPLES = 50
#: The cap must lower the direction's squared one-step residual by at least this share.
MIN_GAIN = 0.01


def capped(predicted: FloatArray, load: FloatArray, limit: float,
           offset: float) -> FloatArray:
    """Return the increments ``predicted`` capped at ``limit / (load + offset)`` in size."""
    return np.sign(predicted) * np.minimum(np.abs(predicted),
                                           power_allowed(load, limit, offset))


def fit_power_cap(measured: FloatArray, predicted: FloatArray,
                  load: FloatArray) -> tuple[float, float]:
    """
    Fit ``|dy| <= c / (L + offset)`` to one direction's one-step increments.

    ``measured``, ``predicted``: measured and model increments of one direction, deg.
    ``load``: measured load at each sample, load units.
    Returns: ``(c, offset)``: the cap in deg x load unit per sample and the offset in load units;
    ``(0, 0)`` when no cap lowers the squared residual by :data:`MIN_GAIN`.
    """
    span = float(np.ptp(load)) if load.size else 0.0
    if not span > 0.0 or predicted.size < MIN_SAMPLES:
        return 0.0, 0.0
    lowest = float(np.min(load))

    def unpack(q: FloatArray) -> tuple[float, float]:
        return float(np.exp(q[0])), -lowest + span * float(np.exp(q[1]))

    def misfit(q: FloatArray) -> FloatArray:
        return measured - capped(predicted, load, *unpack(q))
    base = float(np.sum((measured - predicted) ** 2))
    best, cost = (0.0, 0.0), (1.0 - MIN_GAIN) * 0.5 * base
    for share in (0.05, 0.3, 1.5):
        offset = -lowest + share * span
        seen = np.abs(measured) * (load + offset)
        start = float(np.quantile(seen[np.abs(measured) > 0.0], 0.9)) if np.any(
            np.abs(measured) > 0.0) else 0.0
        if not start > 0.0:
            continue
        fit = least_squares(misfit, [np.log(start), np.log(share)], x_scale=1.0)
        if float(fit.cost) < cost:
            best, cost = unpack(fit.x), float(fit.cost)
    return best

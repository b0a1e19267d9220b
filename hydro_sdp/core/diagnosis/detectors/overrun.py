"""The overrunning load of ``load_dependence``, fitted on the one-step increments (methods 8.2)."""

from __future__ import annotations

from hydro_sdp.core.arrays import FloatArray
from hydro_sdp.core.diagnosis.context import Context
from hydro_sdp.core.diagnosis.residuals import run_increments
from hydro_sdp.core.model.effects import LoadDependence
import numpy as np
from scipy.optimize import least_squares


def inner_range(context: Context, end_share: float) -> tuple[float, float]:
    """Return the angles, deg, of the range seen with ``end_share`` of it left out at each end."""
    low = min(float(np.min(run.record.y)) for run in context.runs)
    high = max(float(np.max(run.record.y)) for run in context.runs)
    margin = end_share * (high - low)
    return low + margin, high - margin


def one_step_samples(context: Context,
                     end_share: float) -> list[tuple[FloatArray, FloatArray, FloatArray]]:
    """Return the measured and predicted increments (deg) and the load of every run."""
    base = context.model.without_effect(LoadDependence.name)
    low, high = inner_range(context, end_share)
    out = []
    for run in context.runs:
        if run.record.load is None:
            continue
        predicted = run_increments(base, run)
        angle = run.record.y[run.start:-1]
        inner = (angle > low) & (angle < high)
        out.append((np.diff(run.record.y[run.start:])[inner], predicted[inner],
                    run.record.load[run.start + 1:][inner]))
    return out


def fit_overrun(measured: FloatArray, predicted: FloatArray,
                load: FloatArray) -> tuple[float, float]:
    """
    Fit ``measured = predicted sqrt(1 + max(0, g (L - onset)))`` by least squares.

    Returns: ``(g, onset)`` in 1/load unit and load units; ``(0, 0)`` when no fit beats the factor
    1.
    """
    span = float(np.ptp(load)) if load.size else 0.0
    if not span > 0.0 or predicted.size < 10:
        return 0.0, 0.0

    def misfit(q: FloatArray) -> FloatArray:
        return measured - predicted * np.sqrt(1.0 + np.maximum(0.0, q[0] * (load / span - q[1])))
    best, cost = (0.0, 0.0), 0.5 * float(np.sum((measured - predicted) ** 2))
    for slope in (-4.0, 4.0):
        for onset in np.quantile(load, (0.1, 0.5, 0.9)).tolist():
            fit = least_squares(misfit, [slope, onset / span])
            if float(fit.cost) < cost:
                best, cost = (float(fit.x[0] / span), float(fit.x[1] * span)), float(fit.cost)
    return best

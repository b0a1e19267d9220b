"""
Fitting the ``stroke_geometry`` effect: how the speed changes along the stroke.

With the map, the delay and the lag fixed, each measured increment is
``dy_k = dt w_k f(y_{k-1}, sign w_k)`` with ``w_k`` the model's speed; ``f``
piecewise-linear over knots in the angle is linear in its knot values, so the
shared factors and the per-direction parts are one (slightly smoothed) least
squares problem. Knots are spread evenly over the angles the joint moved
through, with two more near each end where the cushions act. The factor is
identified only when the data span the stroke (the joint moved through most
of the range between its stops, in both directions) and kept only when it
lowers the simulation error of the experiments.

"""

from __future__ import annotations

from typing import Sequence

from hydro_sdp.core.arrays import FloatArray
from hydro_sdp.core.effects import StrokeGeometry
from hydro_sdp.core.experiments import Experiment
from hydro_sdp.core.timing import delayed_at
import numpy as np
from scipy.signal import lfilter

#: Evenly spread knots over the angles moved through.
KNOTS = 9
#: Share of the range between the stops (or of the angles seen) the motion must cover.
SPAN = 0.6
#: Weight of the smoothing penalty on second differences of the knot values.
SMOOTHING = 1e-3


def model_speeds(experiments: Sequence[Experiment], rate_of: object, delay: int, dt: float,
                 lag: float) -> tuple[FloatArray, FloatArray, FloatArray]:
    """
    Model speed, measured increment and previous angle of every predicted sample.

    Parameters
    ----------
    experiments : sequence of Experiment
        The experiments.
    rate_of : callable
        The static map, commands to deg/s.
    delay : int
        Delay, samples.
    dt : float
        Sample period, s.
    lag : float
        Valve lag time constant, s (0: none).

    Returns
    -------
    tuple of FloatArray
        ``(w, dy, previous)``: deg/s, degrees, degrees.

    """
    pole = float(np.exp(-dt / lag)) if lag > 0.0 else 0.0
    speeds, increments, previous = [], [], []
    for experiment in experiments:
        k = np.arange(experiment.start + 1, experiment.y.size)
        w = np.asarray(rate_of(delayed_at(experiment.v, k, delay)))  # type: ignore[operator]
        if pole > 0.0 and w.size:
            w, _ = lfilter([1.0 - pole], [1.0, -pole], w, zi=[pole * w[0]])
        speeds.append(w)
        increments.append(experiment.y[k] - experiment.y[k - 1])
        previous.append(experiment.y[k - 1])
    return np.concatenate(speeds), np.concatenate(increments), np.concatenate(previous)


def _hats(angles: FloatArray, knots: FloatArray) -> FloatArray:
    """Piecewise-linear basis: column j is 1 at knot j, 0 at the others, flat beyond."""
    clipped = np.clip(angles, knots[0], knots[-1])
    basis = np.zeros((angles.size, knots.size))
    index = np.clip(np.searchsorted(knots, clipped, side='right') - 1, 0, knots.size - 2)
    weight = (clipped - knots[index]) / (knots[index + 1] - knots[index])
    rows = np.arange(angles.size)
    basis[rows, index] = 1.0 - weight
    basis[rows, index + 1] += weight
    return basis


def fit_stroke_geometry(experiments: Sequence[Experiment], rate_of: object, delay: int,
                        dt: float, lag: float,
                        stops: tuple[float | None, float | None] = (None, None)
                        ) -> StrokeGeometry | None:
    """
    Fit a shared angle factor with a per-direction part, if the data span the stroke.

    Parameters
    ----------
    experiments : sequence of Experiment
        The experiments.
    rate_of : callable
        The fitted static map, commands to deg/s.
    delay : int
        Delay, samples.
    dt : float
        Sample period, s.
    lag : float
        Valve lag time constant, s.
    stops : tuple
        End stops seen, degrees (None where none was seen).

    Returns
    -------
    StrokeGeometry or None
        The effect, or None when the data do not span the stroke.

    """
    w, dy, previous = model_speeds(experiments, rate_of, delay, dt, lag)
    peak = float(np.max(np.abs(w))) if w.size else 0.0
    moving = np.abs(w) > 0.1 * peak
    if peak <= 0.0 or np.sum(moving) < 50 * KNOTS:
        return None
    low, high = float(np.min(previous)), float(np.max(previous))
    if stops[0] is not None and stops[1] is not None:
        low, high = float(stops[0]), float(stops[1])
    covered = []
    for sign in (-1.0, 1.0):
        side = moving & (np.sign(w) == sign)
        covered.append(np.ptp(previous[side]) if np.any(side) else 0.0)
    if high <= low or min(covered) < SPAN * (high - low):
        return None
    angles = previous[moving]
    first, last = float(np.min(angles)), float(np.max(angles))
    step = (last - first) / (KNOTS - 1)
    knots = np.unique(np.r_[np.linspace(first, last, KNOTS), first + 0.3 * step,
                            last - 0.3 * step])
    basis = _hats(angles, knots)
    drive = dt * w[moving]
    direction = np.sign(drive)
    design = np.hstack([basis * drive[:, None], basis * (drive * direction)[:, None]])
    target = dy[moving]
    # Smooth: a small penalty on second differences, scaled to the data.
    size = knots.size
    second = np.diff(np.eye(size), 2, axis=0)
    penalty = np.zeros((2 * (size - 2), 2 * size))
    penalty[:size - 2, :size] = second
    penalty[size - 2:, size:] = second
    scale = SMOOTHING * float(np.sqrt(np.sum(design ** 2) / max(design.shape[0], 1)))
    scale *= np.sqrt(design.shape[0])
    solution, *_ = np.linalg.lstsq(np.vstack([design, scale * penalty]),
                                   np.r_[target, np.zeros(penalty.shape[0])], rcond=None)
    shared, part = solution[:size], solution[size:]
    if np.any(shared <= 0.05):
        return None
    asymmetry = np.clip(part / shared, -0.95, 0.95)
    return StrokeGeometry(knots=tuple(knots.tolist()), factors=tuple(shared.tolist()),
                          asymmetry=tuple(asymmetry.tolist()))


def speed_gains(experiments: Sequence[Experiment], rate_of: object, delay: int, dt: float,
                lag: float, geometry: StrokeGeometry) -> list[FloatArray]:
    """
    Per experiment, the geometry's factor at the measured angle before each predicted sample.

    Map fits take these as known gains on the speed (:class:`~hydro_sdp.core.map_fit.FitData`),
    so that the map is fitted to the speed the stroke factor scales.
    """
    gains = []
    for experiment in experiments:
        w, _, previous = model_speeds([experiment], rate_of, delay, dt, lag)
        gains.append(geometry.factor(previous, w))
    return gains

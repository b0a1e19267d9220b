"""
Fitting the ``stroke_geometry`` effect: how the speed changes along the stroke.

The reasoning is in docs/methods.md section 13.5.

"""

from __future__ import annotations

from typing import Literal, Sequence

from hydro_sdp.core.arrays import FloatArray
from hydro_sdp.core.identification.effect_check import at_stop
from hydro_sdp.core.identification.end_stops import STOP_REACH
from hydro_sdp.core.identification.experiment import Experiment
from hydro_sdp.core.model.effects import StrokeGeometry
from hydro_sdp.core.model.first_order import first_order
from hydro_sdp.core.model.timing import delayed_at, SamplePeriod
import numpy as np

#: Evenly spread knots over the angles moved through.
KNOTS = 9
#: Share of the range between the stops (or of the angles seen) the motion must cover.
SPAN = 0.6
#: Weight of the smoothing penalty on second differences of the knot values.
SMOOTHING = 1e-3


def model_speeds(experiments: Sequence[Experiment], rate_of: object, delay: int, dt: SamplePeriod,
                 lag: float) -> tuple[FloatArray, FloatArray, FloatArray]:
    """
    Model speed, measured increment and previous angle of every predicted sample.

    ``rate_of``: the static map, commands to deg/s.
    ``dt``: sample period, s.
    ``lag``: valve lag time constant, s (0: none).
    Returns: ``(w, dy, previous)``: deg/s, degrees, degrees.
    """
    pole = float(np.exp(-dt / lag)) if lag > 0.0 else 0.0
    speeds, increments, previous = [], [], []
    for experiment in experiments:
        k = np.arange(experiment.start + 1, experiment.y.size)
        w = np.asarray(rate_of(delayed_at(experiment.v, k, delay)))  # type: ignore[operator]
        if pole > 0.0 and w.size:
            w = first_order(w, pole, 1.0 - pole, w[0])
        speeds.append(w)
        increments.append(experiment.y[k] - experiment.y[k - 1])
        previous.append(experiment.y[k - 1])
    return np.concatenate(speeds), np.concatenate(increments), np.concatenate(previous)


def hats(angles: FloatArray, knots: FloatArray) -> FloatArray:
    """Piecewise-linear basis: column j is 1 at knot j, 0 at the others, flat beyond."""
    clipped = np.clip(angles, knots[0], knots[-1])
    basis = np.zeros((angles.size, knots.size))
    index = np.clip(np.searchsorted(knots, clipped, side='right') - 1, 0, knots.size - 2)
    weight = (clipped - knots[index]) / (knots[index + 1] - knots[index])
    rows = np.arange(angles.size)
    basis[rows, index] = 1.0 - weight
    basis[rows, index + 1] += weight
    return basis


def stroke_knots(angles: FloatArray) -> FloatArray:
    """
    Knots over the angles moved through: evenly spread, two more near each end (cushions).

    ``angles``: angles the joint moved through, degrees.
    Returns: increasing knots, degrees.
    """
    first, last = float(np.min(angles)), float(np.max(angles))
    step = (last - first) / (KNOTS - 1)
    return np.unique(np.r_[np.linspace(first, last, KNOTS), first + 0.3 * step,
                           last - 0.3 * step])


def penalised_lstsq(blocks: Sequence[FloatArray], smoothed: Sequence[bool],
                    target: FloatArray,
                    ridge: Sequence[float | FloatArray] | None = None
                    ) -> tuple[FloatArray, float]:
    """
    Least squares over column blocks, those of knot values smoothed by a small penalty.

    ``blocks``: design columns, block by block (a block of knot values has one column a knot).
    ``smoothed``: whether each block gets the penalty on second differences of its values.
    ``ridge``: weight of each block's pull towards zero, relative to the data, for the whole block
    or column by column (default: none).
    Returns: ``(solution, sse)``: the coefficients and the sum of squared residuals (without the
    penalty).
    """
    design = np.hstack(blocks)
    rows = []
    column = 0
    for block, smooth in zip(blocks, smoothed):
        size = block.shape[1]
        if smooth and size > 2:
            row = np.zeros((size - 2, design.shape[1]))
            row[:, column:column + size] = np.diff(np.eye(size), 2, axis=0)
            rows.append(row)
        column += size
    # Penalties scaled to the data.
    scale = float(np.sqrt(np.sum(design ** 2) / max(design.shape[0], 1)))
    scale *= np.sqrt(design.shape[0])
    rows = [SMOOTHING * row for row in rows]
    column = 0
    for block, weight in zip(blocks, ridge or [0.0] * len(blocks)):
        size = block.shape[1]
        if np.any(np.asarray(weight) > 0.0):
            row = np.zeros((size, design.shape[1]))
            row[:, column:column + size] = np.diag(np.broadcast_to(weight, (size,)))
            rows.append(row)
        column += size
    penalty = np.vstack(rows) if rows else np.zeros((0, design.shape[1]))
    solution, *_ = np.linalg.lstsq(np.vstack([design, scale * penalty]),
                                   np.r_[target, np.zeros(penalty.shape[0])], rcond=None)
    return solution, float(np.sum((target - design @ solution) ** 2))


#: How a part of the factor is fitted: at every knot, one value for all angles, or not at
#: all (the shared part then stays 1, the per-direction part 0).
Part = Literal['knots', 'constant', 'none']


def fit_factor(angles: FloatArray, drive: FloatArray, target: FloatArray, knots: FloatArray,
               shared: Part = 'knots', direction: Part = 'knots'
               ) -> tuple[FloatArray, FloatArray, float]:
    """
    Fit ``target ~ drive (s(y) + sign(drive) p(y))``, both parts piecewise-linear in the angle.

    ``angles``: angle before each sample, degrees.
    ``drive``: the model's increment of each sample, degrees.
    ``target``: the measured increment, degrees.
    ``knots``: knots, degrees (from :func:`stroke_knots`).
    ``shared``, ``direction``: how the shared part ``s`` and the per-direction part ``p`` are
    fitted.
    Returns: ``(s, p, sse)``: the two parts at the knots and the sum of squared residuals,
    degrees^2.
    """
    size = knots.size
    basis = hats(angles, knots)
    blocks: list[FloatArray] = []
    smoothed: list[bool] = []
    for part, column in ((shared, drive), (direction, drive * np.sign(drive))):
        if part == 'knots':
            blocks.append(np.asarray(basis * column[:, None], dtype=np.float64))
        elif part == 'constant':
            blocks.append(column[:, None])
        smoothed.append(part == 'knots')
    rest: FloatArray = target - drive if shared == 'none' else target
    if not blocks:
        return np.ones(size), np.zeros(size), float(np.sum(rest ** 2))
    solution, sse = penalised_lstsq(blocks, [s for s, p in zip(smoothed, (shared, direction))
                                             if p != 'none'], rest)
    values = []
    index = 0
    for part, default in ((shared, 1.0), (direction, 0.0)):
        if part == 'knots':
            values.append(solution[index:index + size])
            index += size
        elif part == 'constant':
            values.append(np.full(size, solution[index]))
            index += 1
        else:
            values.append(np.full(size, default))
    return values[0], values[1], sse


def geometry_of(knots: FloatArray, shared: FloatArray,
                part: FloatArray | None = None) -> StrokeGeometry | None:
    """
    Return the effect of fitted parts (``f = s (1 + sign(w) p / s)``), None if ``s`` is not > 0.

    ``part``: per-direction part at the knots (None: none).
    Returns: the effect, or None when the shared factor falls to nearly nothing somewhere.
    """
    if np.any(shared <= 0.05):
        return None
    asymmetry = () if part is None else tuple(np.clip(part / shared, -0.95, 0.95).tolist())
    return StrokeGeometry(knots=tuple(knots.tolist()), factors=tuple(shared.tolist()),
                          asymmetry=asymmetry)


def fit_stroke_geometry(experiments: Sequence[Experiment], rate_of: object, delay: int,
                        dt: SamplePeriod, lag: float,
                        stops: tuple[float | None, float | None] = (None, None),
                        reach: float = STOP_REACH) -> StrokeGeometry | None:
    """
    Fit a shared angle factor with a per-direction part, if the data span the stroke.

    ``rate_of``: the fitted static map, commands to deg/s.
    ``dt``: sample period, s.
    ``lag``: valve lag time constant, s.
    ``stops``: end stops seen, degrees (None where none was seen).
    ``reach``: how near a stop the joint counts as sitting at it, degrees: samples there that drive
    it into the stop are left out (:func:`.effect_check.at_stop`).
    Returns: the effect, or None when the data do not span the stroke.
    """
    w, dy, previous = model_speeds(experiments, rate_of, delay, dt, lag)
    peak = float(np.max(np.abs(w))) if w.size else 0.0
    moving = (np.abs(w) > 0.1 * peak) & ~at_stop(previous, w, stops, reach)
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
    knots = stroke_knots(angles)
    shared, part, _ = fit_factor(angles, dt * w[moving], dy[moving], knots)
    return geometry_of(knots, *unit_mean_per_direction(knots, shared, part, angles,
                                                       np.sign(w[moving])))


def unit_mean_per_direction(knots: FloatArray, shared: FloatArray, part: FloatArray,
                            angles: FloatArray, signs: FloatArray
                            ) -> tuple[FloatArray, FloatArray]:
    """
    Scale the factor of each direction to a mean of 1 over the angles it was seen at.

    ``shared``, ``part``: shared and per-direction parts at the knots (``f = s + sign(w) p``).
    ``angles``: angle of each sample the factor was fitted on, degrees.
    ``signs``: direction of motion of each of those samples (+1, -1).
    Returns: the shared and per-direction parts, rescaled.
    """
    basis = hats(angles, knots)
    sides = []
    for sign in (1.0, -1.0):
        seen = signs == sign
        at_knots = shared + sign * part
        mean = float(np.mean(basis[seen] @ at_knots)) if np.any(seen) else 1.0
        sides.append(at_knots / mean if mean > 0.0 else at_knots)
    up, down = sides
    return 0.5 * (up + down), 0.5 * (up - down)


def speed_gains(experiments: Sequence[Experiment], rate_of: object, delay: int, dt: SamplePeriod,
                lag: float, geometry: StrokeGeometry) -> list[FloatArray]:
    """
    Per experiment, the geometry's factor at the measured angle before each predicted sample.

    Map fits take these as known gains on the speed (:class:`~.map_fit.FitData`),
    so that the map is fitted to the speed the stroke factor scales.
    """
    gains = []
    for experiment in experiments:
        w, _, previous = model_speeds([experiment], rate_of, delay, dt, lag)
        gains.append(geometry.factor(previous, w))
    return gains

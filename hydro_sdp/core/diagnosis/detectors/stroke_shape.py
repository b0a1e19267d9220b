"""Detector of a speed that changes along the stroke alike both ways (methods 8.2)."""

from __future__ import annotations

from dataclasses import replace
from typing import NamedTuple

from hydro_sdp.core.arrays import FloatArray
from hydro_sdp.core.diagnosis.context import Context
from hydro_sdp.core.diagnosis.detectors.angle import directional_signature, noise_of
from hydro_sdp.core.diagnosis.detectors.base import EffectDetector
from hydro_sdp.core.diagnosis.residuals import Run
from hydro_sdp.core.diagnosis.results import Candidate, Signature, Trial
from hydro_sdp.core.identification.stalls import stalled
from hydro_sdp.core.identification.stroke_fit import (
    geometry_of, hats, KNOTS, penalised_lstsq, stroke_knots)
from hydro_sdp.core.model.effects import DirectionDependentDelay
from hydro_sdp.core.model.joint_model import JointModel
import numpy as np

#: Share of the squared residual left by map and transients that the shared angle factor
#: must remove (where both directions are seen) for the data to show the word's signature.
SIGNATURE_SHARE = 0.1
#: ...and at least this many times what an opposite factor removes there.
DOMINANCE = 1.5
#: Least share of the angles moved through that both directions must move through for
#: the shared and the opposite factor to be told apart.
MIN_OVERLAP = 0.25
#: Time after the model's delay from which a sample counts, s (before it the speed rises).
SETTLE = 0.1
#: Time after a command change within which a wrong delay or lag leaves its transient, s.
TRANSIENT = 1.0
#: Pull of the per-direction part of the factor towards zero, relative to the data.
RIDGE = 0.05


class Parts(NamedTuple):
    """
    What each part of an angle factor explains of the measured increments.

    Parameters
    ----------
    base : float
        Squared residual of the model under test over the samples the parts are
        compared on, degrees^2.
    command : float
        Left by factors of the model's speed (per direction) and of the time since the
        command changed (both directions alike): what a refitted map, delay or lag does.
    shared : float
        Left by that and a factor of the angle shared by both directions.
    opposite : float
        Left by that and a factor of the angle opposite for the two directions.

    """

    base: float
    command: float
    shared: float
    opposite: float

    @property
    def signature(self) -> bool:
        """Whether the shared angle factor explains clearly more than the opposite, and enough."""
        gain = self.command - self.shared
        return gain > DOMINANCE * (self.command - self.opposite) and \
            gain >= SIGNATURE_SHARE * self.command


class Samples(NamedTuple):
    """
    The samples an angle factor is fitted on.

    Parameters
    ----------
    angles : FloatArray
        Angle before each sample, degrees.
    drive, target : FloatArray
        The model's and the measured increment, degrees.
    since : FloatArray
        Time since the command last changed, s.

    """

    angles: FloatArray
    drive: FloatArray
    target: FloatArray
    since: FloatArray


def _since_change(v: FloatArray) -> FloatArray:
    """Return the samples since the command last changed, at each sample."""
    changes = np.r_[0, np.flatnonzero(np.diff(v)) + 1]
    return np.arange(v.size) - changes[np.searchsorted(changes, np.arange(v.size),
                                                       side='right') - 1]


def stroke_samples(context: Context) -> Samples:
    """Return the samples of motion away from the stops."""
    model = context.model
    split = model.effect(DirectionDependentDelay.name)
    delay = max(split.positive, split.negative) if isinstance(split, DirectionDependentDelay) \
        else model.delay
    angles, drives, targets, times, stalls = [], [], [], [], []
    travel = (min(float(np.min(r.record.y)) for r in context.runs),
              max(float(np.max(r.record.y)) for r in context.runs))
    for run, residual in zip(context.runs, context.base):
        dy = np.diff(run.record.y[run.start:])
        angles.append(run.record.y[run.start:-1])
        drives.append(dy - residual)
        targets.append(dy)
        times.append(context.dt * _since_change(run.record.v)[run.start + 1:])
        # A stall (a load the valve cannot lift) is no factor of the angle.
        stalls.append(stalled(model, run.record, run.dt, travel, run.exogenous)[run.start:-1])
    y, drive, dy = np.concatenate(angles), np.concatenate(drives), np.concatenate(targets)
    since = np.concatenate(times)
    # The stops: those the data show (extreme angles, or where the segmentation saw the
    # joint held) and the model's.
    found = context.segmentation.end_stops if context.segmentation is not None else (None,
                                                                                     None)
    limits = model.angle_limits or (None, None)
    low = max(x for x in (float(np.min(y)), found[0], limits[0]) if x is not None)
    high = min(x for x in (float(np.max(y)), found[1], limits[1]) if x is not None)
    noise = float(np.median([noise_of(r.record.y) for r in context.runs]))
    band = max(0.5, 10.0 * noise)
    # Held still while driven near a stop (contact, play taken up against it) counts as
    # the stop's too.
    near = max(5.0 * band, 0.1 * (high - low))
    held = np.abs(dy) < 0.2 * np.abs(drive)
    keep = (since > delay + SETTLE) & ~np.concatenate(stalls) & \
        ~((drive > 0.0) & ((y > high - band) | (held & (y > high - near)))) & \
        ~((drive < 0.0) & ((y < low + band) | (held & (y < low + near))))
    if model.angle_limits is not None:
        # Where the model's stops cut the increment, no factor scales it.
        bottom, top = model.angle_limits
        keep &= (y > bottom) & (y < top) & (y + drive > bottom) & (y + drive < top)
    peak = float(np.max(np.abs(drive[keep]))) if np.any(keep) else 0.0
    keep &= np.abs(drive) > 0.05 * peak
    return Samples(y[keep], drive[keep], dy[keep], since[keep])


def factor_parts(samples: Samples) -> Parts:
    """
    Return what a shared and an opposite angle factor explain beyond map and transients.

    ``samples``: the samples a factor is fitted on.
    Returns: the squared residuals, degrees^2.
    """
    y, up = samples.angles, samples.drive > 0.0
    inside = np.zeros(y.size, dtype=bool)
    if np.any(up) and not np.all(up):
        low = max(float(np.min(y[up])), float(np.min(y[~up])))
        high = min(float(np.max(y[up])), float(np.max(y[~up])))
        if high - low >= MIN_OVERLAP * float(np.ptp(y)):
            inside = (y >= low) & (y <= high)
    drive, target = samples.drive[inside], samples.target[inside]
    base = float(np.sum((target - drive) ** 2))
    if np.count_nonzero(inside) < 50 * KNOTS:
        return Parts(base, base, base, base)
    sign = np.sign(drive)[:, None]
    speed = np.abs(drive)
    by_speed = hats(speed, stroke_knots(speed)) * drive[:, None] if np.ptp(speed) > 0.0 \
        else drive[:, None]
    known = [by_speed, by_speed * sign]
    time = np.minimum(samples.since[inside], TRANSIENT)
    if np.ptp(time) > 0.0:
        # Zero once steady, the same for both directions (a delay or lag is).
        known.append(hats(time, stroke_knots(time))[:, :-1] * drive[:, None])
    by_angle = hats(y[inside], stroke_knots(y[inside])) * drive[:, None]
    smooth = [True] * (len(known) + 1)
    return Parts(base, penalised_lstsq(known, smooth[1:], target)[1],
                 penalised_lstsq(known + [by_angle], smooth, target)[1],
                 penalised_lstsq(known + [by_angle * sign], smooth, target)[1])


def fit_shape(samples: Samples, knots: FloatArray) -> tuple[FloatArray, FloatArray]:
    """
    Fit the shared factor and its per-direction part (cushions, load) at ``knots``.

    Returns: the shared factor and the per-direction part at the knots.
    """
    basis = hats(samples.angles, knots)
    up = samples.drive > 0.0
    seen = np.minimum(basis[up].sum(axis=0), basis[~up].sum(axis=0))
    alone = seen < 0.1 * np.maximum(basis[up].sum(axis=0), basis[~up].sum(axis=0))
    by_angle = basis * samples.drive[:, None]
    solution, _ = penalised_lstsq([by_angle, by_angle * np.sign(samples.drive)[:, None]],
                                  [True, True], samples.target,
                                  ridge=[0.0, np.where(alone, RIDGE, 0.0)])
    return solution[:knots.size], solution[knots.size:]


class StrokeGeometryDetector(EffectDetector):
    """The speed changes along the stroke alike for both directions: fit the angle factor."""

    word = 'stroke_geometry'
    description = 'the speed changes along the stroke alike for both directions (linkage, ' \
        'cushions)'
    remedy = 'effect, a piecewise-linear angle factor shared by both directions'
    feature = 'angle'
    state = 'angle'

    def fit_effect(self, context: Context) -> Trial:
        """Fit the factor where the data show it alike for both directions, and score it."""
        samples = stroke_samples(context)
        if samples.angles.size < 50 * KNOTS or np.ptp(samples.angles) <= 0.0:
            return Candidate(self.word, True, evidence='too little steady motion away from '
                             'the stops to fit a factor along the stroke'), None
        parts = factor_parts(samples)
        # Shares of what the map, delay and lag leave: the base of the signature test.
        shares = (f'beyond the map, a shared factor removes '
                  f'{100 * (parts.command - parts.shared) / max(parts.command, 1e-300):.3g} % '
                  f'of the residual where both directions are seen, an opposite one '
                  f'{100 * (parts.command - parts.opposite) / max(parts.command, 1e-300):.3g} %')
        if not parts.signature:
            # Without its signature the word is not tried: an opposite factor is
            # angle_dependent_velocity, a speed scale the map's.
            return Candidate(self.word, True, evidence=f'the speed does not change along '
                             f'the stroke alike for both directions ({shares})'), None
        knots = stroke_knots(samples.angles)
        shared, part = fit_shape(samples, knots)
        geometry = geometry_of(knots, shared, part)
        if geometry is None:
            return Candidate(self.word, True, evidence='the fitted factor falls to nothing '
                             'along the stroke'), None
        ratio = float(np.max(shared) / np.min(shared))
        trial, augmented = context.score(
            self.word, context.model.with_effect(geometry),
            {'knots': list(geometry.knots), 'factors': list(geometry.factors),
             'asymmetry': list(geometry.asymmetry)},
            f'the speed for a given command changes x{ratio:.3g} along the stroke '
            f'[{knots[0]:.3g}, {knots[-1]:.3g}] deg alike for both directions ({shares})')
        # Motion faster or slower at the same angles both ways is the linkage, whatever else
        # could shrink the residual there.
        return replace(trial, signature_match=trial.significant), augmented

    def signature(self, model: JointModel, augmented: JointModel, run: Run) -> Signature:
        """Return the residual against the angle, the two directions of motion apart."""
        return directional_signature(self.word, model, augmented, run)

"""Detectors of what the angle does: end stops, speed that depends on the angle (methods 8.2)."""

from __future__ import annotations

from dataclasses import replace
import math

from hydro_sdp.core.arrays import FloatArray
from hydro_sdp.core.diagnosis.context import Context
from hydro_sdp.core.diagnosis.detectors.base import Detector, EffectDetector, feature_signature
from hydro_sdp.core.diagnosis.residuals import Run, velocity_residuals
from hydro_sdp.core.diagnosis.results import Candidate, Signature, Trial
from hydro_sdp.core.model.effects import AngleDependentVelocity
from hydro_sdp.core.model.joint_model import JointModel
from hydro_sdp.core.model.simulation import speed_profile
from hydro_sdp.core.model.timing import delayed_at
import numpy as np
from scipy.optimize import least_squares


#: Shortest contact that shows a stop: the joint held still while driven, s.
MIN_CONTACT = 0.3


def noise_of(angles: FloatArray) -> float:
    """Robust angle noise from second differences (motion is mostly steady), degrees."""
    second = np.diff(angles, 2)
    return float(1.4826 * np.median(np.abs(second)) / math.sqrt(6.0)) if second.size else 0.0


def held_at_stops(context: Context) -> tuple[float | None, float | None, int]:
    """
    Return the angles the joint is held still at while driven on, low and high side.

    Returns: ``(low, high, samples)``: the stop angles (None where there is no contact for at least
    :data:`MIN_CONTACT` s) and the contact samples.
    """
    # Over a fifth of a second, so that slow motion stands out of the noise.
    window = max(2, int(round(0.2 / context.dt)))
    tau = context.model.longest_delay_samples(context.dt)
    angles, steps, moves, drives = [], [], [], []
    for run in context.runs:
        record = run.record
        speed = speed_profile(context.model, record.v, run.dt, v_before=float(record.v[0]))
        travel = np.cumsum(np.r_[0.0, run.dt * speed[run.start + 1:]])
        y = record.y[run.start:]
        if y.size > window:
            angles.append(y[:-window])
            steps.append(y[window:] - y[:-window])
            moves.append(travel[window:] - travel[:-window])
            # The command that drives the window: held through it, else no drive.
            first = delayed_at(record.v, np.arange(run.start + 1, len(record) - window + 1),
                               tau)
            last = delayed_at(record.v, np.arange(run.start + window, len(record)), tau)
            drives.append(np.where(first == last, first - context.rest, 0.0))
    if not angles:
        return None, None, 0
    y, dy, move = np.concatenate(angles), np.concatenate(steps), np.concatenate(moves)
    drive = np.concatenate(drives)
    noise = max(float(np.median([noise_of(r.record.y) for r in context.runs])), 1e-6)
    band = max(0.5, 10.0 * noise)
    still = (np.abs(move) > 10.0 * noise) & (np.abs(dy) < 0.2 * np.abs(move))
    needed = int(round(MIN_CONTACT / context.dt))
    low_end, high_end = float(np.min(y)), float(np.max(y))
    inner = (y > low_end + band) & (y < high_end - band)
    stops: list[float | None] = []
    contact = 0
    for sign in (-1.0, 1.0):
        # The smallest drive seen moving the joint that way away from the ends.
        moving = inner & (np.sign(drive) == sign) & (np.sign(dy) == sign) & \
            (np.abs(dy) > 10.0 * noise)
        edge = float(np.min(np.abs(drive[moving]))) if np.any(moving) else math.inf
        driven = still & (np.sign(move) == sign) & (np.sign(drive) == sign) & \
            (np.abs(drive) >= edge)
        dwell = outermost_dwell(sign * y[driven], band, needed)
        if dwell is None:
            stops.append(None)
            continue
        held = driven & (np.abs(y - sign * dwell) < band)
        # A stop is never passed: the joint may rebound beyond it for moments (a boom
        # dropped onto its stop at full duty), not for longer than it is held there.
        beyond = int(np.count_nonzero(sign * y - dwell > band))
        if np.count_nonzero(held) >= needed and beyond < np.count_nonzero(held):
            stops.append(float(np.median(y[held])))
            contact += int(np.count_nonzero(held))
        else:
            stops.append(None)
    return stops[0], stops[1], contact


def outermost_dwell(outward: FloatArray, band: float, needed: int) -> float | None:
    """
    Return the outermost value near which at least ``needed`` of ``outward`` gather.

    ``outward``: angles of the samples held still while driven, signed so that larger is further
    towards the stop.
    ``band``: half-width of a dwell, degrees.
    Returns: the median of the outermost ``2 band`` wide window holding ``needed`` samples (in the
    signed angles), None where no window does.
    """
    values = np.sort(outward)
    if values.size < needed:
        return None
    first = np.searchsorted(values, values - 2.0 * band, side='right')
    counts = np.arange(1, values.size + 1) - first
    full = np.flatnonzero(counts >= needed)
    if full.size == 0:
        return None
    last = int(full[-1])
    return float(np.median(values[first[last]:last + 1]))


def directional_signature(word: str, model: JointModel, augmented: JointModel,
                          run: Run) -> Signature:
    """Return the residual against the angle with the direction of the model's motion."""
    signature = feature_signature(word, 'angle', model, augmented, run)
    record = run.record
    speed = speed_profile(model, record.v, run.dt, v_before=float(record.v[0]))
    return replace(signature, signs=np.sign(speed[run.start + 1:]))


class AngleLimitsDetector(Detector):
    """The joint stops at end stops the model lacks: take the stops seen in the data."""

    word = 'angle_limits'
    description = 'the joint stops at end stops the model lacks'
    remedy = 'the stops seen in the data'
    feature = 'angle'
    state = 'angle'

    def fit(self, context: Context) -> Trial:
        """Give the model the stops the joint is held at while driven, and score it."""
        low, high, contact = held_at_stops(context)
        if low is None and high is None:
            return Candidate(self.word, True, evidence='the joint is never held still while '
                             'driven'), None
        current = context.model.angle_limits
        # A side without contact keeps the model's stop, or lies beyond every angle seen
        # by the whole range seen (no stop was seen there: none to put near the data).
        angles = np.concatenate([r.record.y for r in context.runs])
        seen = max(float(np.ptp(angles)), 1.0)
        spare = current or (float(np.min(angles)) - seen, float(np.max(angles)) + seen)
        stops = (spare[0] if low is None else min(low, spare[1] - 1e-6),
                 spare[1] if high is None else max(high, spare[0] + 1e-6))
        if current is not None and np.allclose(current, stops, atol=0.1):
            return Candidate(self.word, True), None
        candidate = replace(context.model, angle_limits=stops)
        held = ' and '.join(f'{angle:.3g} deg' for angle in (low, high) if angle is not None)
        trial, augmented = context.score(
            self.word, candidate, {'angle_limits': list(stops)},
            f'the joint is held still at {held} while the command drives it on beyond its '
            f'dead-zone ({contact * context.dt:.3g} s of contact)')
        # Motion that ends at one angle whenever it is driven there is a stop, whatever
        # else could shrink the residual there; stops moved (backlash shifts where the
        # sensor stops) compete on gain like any other word.
        return replace(trial, signature_match=current is None and trial.significant), augmented

    def signature(self, model: JointModel, augmented: JointModel, run: Run) -> Signature:
        """Return the residual against the angle, the two directions of motion apart."""
        return directional_signature(self.word, model, augmented, run)


class AngleDependentVelocityDetector(EffectDetector):
    """The speed depends on the angle (geometry, gravity): regress the residual on it."""

    word = 'angle_dependent_velocity'
    description = 'the speed depends on the angle (geometry, gravity)'
    remedy = 'effect, regression on the angle'
    feature = 'angle'
    state = 'angle'

    def fit_effect(self, context: Context) -> Trial:
        """Fit amplitude and phase by regression, polish on the residuals, and score."""
        # eps ~ dt |w| (A cos y + B sin y) with A = c cos(phi), B = -c sin(phi): a linear
        # regression of the velocity residual on the model speed times the angle's cosine
        # and sine (the library term 'q cos(y) sgn(q)' of docs/methods.md 8.6) gives c and
        # phi at once.
        rows, targets = [], []
        for run, residual in zip(context.runs, context.base):
            record = run.record
            speed = run.dt * np.abs(speed_profile(context.model, record.v, run.dt,
                                                  v_before=float(record.v[0]))[run.start + 1:])
            angle = np.radians(record.y[run.start:-1])
            rows.append(np.column_stack([speed * np.cos(angle), speed * np.sin(angle)]))
            targets.append(residual)
        a, b = np.linalg.lstsq(np.concatenate(rows), np.concatenate(targets), rcond=None)[0]

        def effect_of(p: FloatArray) -> AngleDependentVelocity:
            return AngleDependentVelocity(min(math.hypot(p[0], p[1]), 0.95),
                                          math.degrees(math.atan2(-p[1], p[0])) % 360.0)

        def residuals(p: FloatArray) -> FloatArray:
            return np.concatenate(velocity_residuals(context.model.with_effect(effect_of(p)),
                                                     context.runs))
        # Polish on the exact one-step residuals (the regression ignores the end stops).
        result = least_squares(residuals, np.array([a, b]), method='lm', max_nfev=100)
        effect = effect_of(result.x)
        amplitude, phase = effect.amplitude, effect.phase
        return context.score(self.word, context.model.with_effect(effect),
                             {'amplitude': amplitude, 'phase': phase},
                             f'the speed for a given command changes with the angle by '
                             f'{100 * amplitude:.3g} % (phase {phase:.3g} deg)')

    def signature(self, model: JointModel, augmented: JointModel, run: Run) -> Signature:
        """Return the residual against the angle, the two directions of motion apart."""
        return directional_signature(self.word, model, augmented, run)

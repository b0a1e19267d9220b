"""Detectors of what the angle does: end stops, speed that depends on the angle."""

from __future__ import annotations

from dataclasses import replace
import math

from hydro_sdp.core.arrays import FloatArray
from hydro_sdp.core.diagnosis.context import Context
from hydro_sdp.core.diagnosis.detectors.base import Detector
from hydro_sdp.core.diagnosis.residuals import velocity_residuals
from hydro_sdp.core.diagnosis.results import Candidate, Trial
from hydro_sdp.core.effects import AngleDependentVelocity as AngleSpeed
from hydro_sdp.core.simulation import speed_profile
import numpy as np
from scipy.optimize import least_squares


class AngleLimits(Detector):
    """The joint stops at end stops the model lacks: take the stops seen in the data."""

    word = 'angle_limits'
    description = 'the joint stops at end stops the model lacks'
    remedy = 'the stops seen in the data'
    feature = 'angle'

    def fit(self, context: Context) -> Trial:
        """Give the model the stops the segmentation found, and score it."""
        low, high = context.segmentation.end_stops
        if low is None and high is None:
            return Candidate(self.word, True, evidence='the joint is never held still while '
                             'driven'), None
        angles = np.concatenate([r.record.y for r in context.runs])
        low = float(np.min(angles)) - 1e-6 if low is None else low
        high = float(np.max(angles)) + 1e-6 if high is None else high
        if context.model.angle_limits is not None and \
                np.allclose(context.model.angle_limits, (low, high), atol=0.1):
            return Candidate(self.word, True), None
        candidate = replace(context.model, angle_limits=(low, high))
        return context.score(self.word, candidate, {'angle_limits': [low, high]},
                             f'the joint is held still at {low:.3g} and {high:.3g} deg '
                             'although the command drives it on')


class AngleDependentVelocity(Detector):
    """The speed depends on the angle (geometry, gravity): regress the residual on it."""

    word = 'angle_dependent_velocity'
    description = 'the speed depends on the angle (geometry, gravity)'
    remedy = 'effect, regression on the angle'
    feature = 'angle'

    def fit(self, context: Context) -> Trial:
        """Fit amplitude and phase by regression, polish on the residuals, and score."""
        if context.model.effect(AngleSpeed.name) is not None:
            return Candidate(self.word, False), None
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

        def effect_of(p: FloatArray) -> AngleSpeed:
            return AngleSpeed(min(math.hypot(p[0], p[1]), 0.95),
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

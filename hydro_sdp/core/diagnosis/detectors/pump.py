"""Detector of a joint slowed while others move: ``flow_sharing`` (methods 8.2)."""

from __future__ import annotations

from hydro_sdp.core.arrays import FloatArray
from hydro_sdp.core.diagnosis.context import Context
from hydro_sdp.core.diagnosis.detectors.base import EffectDetector
from hydro_sdp.core.diagnosis.results import Candidate, Trial
from hydro_sdp.core.identification.held_out import WindowErrors
from hydro_sdp.core.model.effects import FlowSharing
from hydro_sdp.core.model.exogenous_signals import summed_other_speeds
from hydro_sdp.core.model.joint_model import JointModel
import numpy as np
from scipy.optimize import minimize


#: Time the other joints must move for, s, for the records to hold a cause to share flow.
MIN_MOVING = 1.0
#: Travel within a second, of an angle averaged over half a second, that counts as moving,
#: deg: a still joint's sensor noise, differentiated, reads as speed.
MIN_TRAVEL = 1.0


def moving_time(context: Context) -> float:
    """Return the time, s, the other joints travel :data:`MIN_TRAVEL` in a second, summed."""
    total = 0
    for run in context.runs:
        others = run.record.others
        if others is None or len(others) < 2:
            continue
        width = max(1, int(round(0.5 / run.dt)))
        second = max(1, int(round(1.0 / run.dt)))
        kernel = np.ones(width) / width
        angles = np.asarray(others, dtype=float).reshape(len(others), -1)
        for column in angles.T:
            smooth = np.convolve(column, kernel, mode='valid')
            if smooth.size > second:
                travel = np.abs(smooth[second:] - smooth[:-second])
                total += int(np.count_nonzero(travel >= MIN_TRAVEL))
    return total * context.dt


def other_speed_sums(context: Context) -> list[FloatArray | None]:
    """Return the summed other joints' speed per residual sample of each run, deg/s."""
    return [summed_other_speeds(run.exogenous, run.start) for run in context.runs]


class FlowSharingDetector(EffectDetector):
    """The joint slows while other joints move: fit a shared pump-flow limit."""

    word = 'flow_sharing'
    description = 'the joint slows while other joints move (one pump)'
    remedy = 'effect, pump-flow limit fitted'
    feature = 'others'
    state = 'others_speed'

    def fit_effect(self, context: Context) -> Trial:
        """Fit the limit and the other joints' full speeds, and score them."""
        sums = other_speed_sums(context)
        if all(s is None for s in sums):
            return Candidate(self.word, False, evidence='the records carry no other joints '
                             '(JointState of one joint)'), None
        moving = np.concatenate([s for s in sums if s is not None])
        top = float(np.quantile(moving, 0.99)) if moving.size else 0.0
        if not top > 1.0:
            return Candidate(self.word, False, evidence='the other joints never move '
                             f'(summed speed below {max(top, 0.0):.2g} deg/s)'), None
        moved = moving_time(context)
        if moved < MIN_MOVING:
            why = ('no other joint moves on the supply in the runs (it travels '
                   f'{MIN_TRAVEL:g} deg within a second for {moved:.2g} s; {MIN_MOVING:g} s '
                   'needed)')
            return Candidate(self.word, False, evidence=why, refused=why), None
        levels = np.unique(np.concatenate([r.record.v for r in context.runs]))
        rates = context.model.rate(levels)
        # Full demand: the top speed in each direction, where the joint alone takes the pump.
        full = (float(np.max(rates)), float(-np.min(rates)))
        if not min(full) > 0.0:
            return Candidate(self.word, False, evidence='the model does not move both ways '
                             'at the commands recorded'), None

        def model_with(p: FloatArray) -> JointModel:
            limit, up, down = np.exp(np.clip(p, -6.0, 6.0)).tolist()
            return context.model.with_effect(FlowSharing(limit, *full, top * up, top * down))

        errors = WindowErrors(context.runs)

        def simulation_error(p: FloatArray) -> float:
            return errors.compare([model_with(p)])[0]
        # Fitted on the simulation error over windows from the measured angle: the share a
        # joint loses adds up over a move, which the one-step residual weighs too little
        # against the valve's transients, and a whole record's error drifts with every
        # other error of the model. The error is flat where the factor is 1: start from
        # the best of a grid.
        grid = [np.log([limit, up, down]) for limit in (0.8, 1.1, 1.6)
                for up in (0.5, 1.0, 2.0) for down in (0.5, 1.0, 2.0)]
        # The error surface is rough (a share cut integrates into a drift): polish the
        # best two starts of the grid and keep the better.
        starts = sorted(grid, key=simulation_error)[:2]
        fits = [minimize(simulation_error, start, method='Nelder-Mead',
                         options={'xatol': 1e-3, 'fatol': 1e-6, 'maxfev': 120})
                for start in starts]
        best = min(fits, key=lambda fit: float(fit.fun)).x
        best = np.clip(best, -6.0, 6.0)
        augmented = model_with(best)
        effect = augmented.effect(self.word)
        assert isinstance(effect, FlowSharing)
        both = effect.limit / (1.0 + top / max(effect.other_positive, effect.other_negative))
        return context.score(
            self.word, augmented, {'limit': effect.limit, 'full_positive': effect.full_positive,
                                   'full_negative': effect.full_negative,
                                   'other_positive': effect.other_positive,
                                   'other_negative': effect.other_negative},
            f'while the other joints move ({top:.3g} deg/s) the speed at full command drops '
            f'to x{min(both, 1.0):.2f} or less (pump limit {effect.limit:.3g} full demands)')

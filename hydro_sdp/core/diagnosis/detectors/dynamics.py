"""Detectors of the valve's and the linkage's dynamics: valve lag, backlash."""

from __future__ import annotations

from hydro_sdp.core.diagnosis.context import Context
from hydro_sdp.core.diagnosis.detectors.base import EffectDetector
from hydro_sdp.core.diagnosis.results import Trial
from hydro_sdp.core.model.effects import Backlash, ValveLag


class ValveLagDetector(EffectDetector):
    """
    The speed approaches each new level with a first-order lag: fit its time constant.

    A model with a lag has it fitted again: a time constant that is far off (a short
    lag traded for a longer delay) is named and corrected like a missing one.

    """

    word = 'valve_lag'
    description = 'the speed approaches each new level with a lag'
    remedy = 'effect, time constant fitted'
    feature = 'events'
    state = 'since_change'
    refits = True

    def fit_effect(self, context: Context) -> Trial:
        """Fit the time constant between a fifth of a sample and 2 s, and score it."""
        finding = 'after each command change the speed settles with a time constant of {} s'
        present = context.model.effect(self.word)
        if isinstance(present, ValveLag):
            finding += f', not {present.time_constant:.3g} s'
        return self.fit_one_parameter(context, ValveLag, 'time_constant', (0.2 * context.dt, 2.0),
                                      finding, log=True)


class BacklashDetector(EffectDetector):
    """After a reversal the joint loses motion: fit the play."""

    word = 'backlash'
    description = 'after a reversal the joint loses motion'
    remedy = 'effect, play fitted'
    feature = 'reversals'
    state = 'reversals'

    def fit_effect(self, context: Context) -> Trial:
        """Fit the play between 0 and 10 degrees, and score it."""
        return self.fit_one_parameter(
            context, Backlash, 'play', (0.0, 10.0),
            'after each reversal the angle stands still while {} deg of play are taken up')

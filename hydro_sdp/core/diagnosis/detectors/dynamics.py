"""Detectors of the valve's and the linkage's dynamics: valve lag, backlash."""

from __future__ import annotations

from hydro_sdp.core.diagnosis.context import Context
from hydro_sdp.core.diagnosis.detectors.base import Detector
from hydro_sdp.core.diagnosis.results import Candidate, Trial
from hydro_sdp.core.effects import Backlash as Play, ValveLag as Lag


class ValveLag(Detector):
    """The speed approaches each new level with a first-order lag: fit its time constant."""

    word = 'valve_lag'
    description = 'the speed approaches each new level with a lag'
    remedy = 'effect, time constant fitted'
    feature = 'events'

    def fit(self, context: Context) -> Trial:
        """Fit the time constant between a fifth of a sample and 2 s, and score it."""
        if context.model.effect(Lag.name) is not None:
            return Candidate(self.word, False), None
        constant = context.fit_scalar(lambda T: context.model.with_effect(Lag(T)),
                                      (0.2 * context.dt, 2.0), log=True)
        candidate = context.model.with_effect(Lag(constant))
        return context.score(self.word, candidate, {'time_constant': constant},
                             f'after each command change the speed settles with a time '
                             f'constant of {constant:.3g} s')


class Backlash(Detector):
    """After a reversal the joint loses motion: fit the play."""

    word = 'backlash'
    description = 'after a reversal the joint loses motion'
    remedy = 'effect, play fitted'
    feature = 'reversals'

    def fit(self, context: Context) -> Trial:
        """Fit the play between 0 and 10 degrees, and score it."""
        if context.model.effect(Play.name) is not None:
            return Candidate(self.word, False), None
        play = context.fit_scalar(lambda b: context.model.with_effect(Play(b)), (0.0, 10.0))
        candidate = context.model.with_effect(Play(play))
        return context.score(self.word, candidate, {'play': play},
                             f'after each reversal the angle stands still while {play:.3g} '
                             'deg of play are taken up')

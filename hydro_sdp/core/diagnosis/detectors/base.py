"""What a detector is: one word, how it is fitted and how it shows (methods 8.5)."""

from __future__ import annotations

from abc import ABC, abstractmethod
from typing import Callable, ClassVar

from hydro_sdp.core.diagnosis.context import Context
from hydro_sdp.core.diagnosis.residuals import Run, velocity_residuals
from hydro_sdp.core.diagnosis.results import Candidate, Feature, Signature, Trial
from hydro_sdp.core.model.effects import Effect
from hydro_sdp.core.model.exogenous_signals import summed_other_speeds
from hydro_sdp.core.model.joint_model import JointModel
from hydro_sdp.core.model.simulation import speed_profile
from hydro_sdp.core.model.timing import delayed_at
import numpy as np

#: What the x axis of each feature's signature shows.
FEATURE_LABELS: dict[Feature, str] = {
    'command': 'delayed command',
    'angle': 'joint angle (deg)',
    'events': 'samples after a delayed command change (signed by the change)',
    'reversals': 'samples after a reversal of motion (signed by the new direction)',
    'others': "other joints' speed, summed (deg/s)",
}


class Detector(ABC):
    """One effect of the vocabulary: what the model misses, how it is fitted, how it shows."""

    #: Vocabulary word (also the effect's key in a model file when it is an effect).
    word: ClassVar[str]
    #: What the model misses, in a few words.
    description: ClassVar[str]
    #: How the effect is added to the model.
    remedy: ClassVar[str]
    #: What the residual signature is drawn against.
    feature: ClassVar[Feature]
    #: The state of the SDP analysis whose dependence names the word
    #: (:mod:`hydro_sdp.core.diagnosis.naming`).
    state: ClassVar[str]

    @abstractmethod
    def fit(self, context: Context) -> Trial:
        """
        Add the effect to the model under test, fit it and score it.

        Returns: the candidate, and the augmented model (None when there is none to keep).
        """

    def signature(self, model: JointModel, augmented: JointModel, run: Run) -> Signature:
        """Return the residual signature of the effect on one run, before and after adding it."""
        return feature_signature(self.word, self.feature, model, augmented, run)


class EffectDetector(Detector):
    """An effect of :mod:`hydro_sdp.core.model.effects`, tried on a model without it."""

    #: Whether the effect is fitted again when the model has it already.
    refits: ClassVar[bool] = False

    def fit(self, context: Context) -> Trial:
        """Fit and score the effect; not applicable when the model has it, unless refitted."""
        if context.model.effect(self.word) is not None and not self.refits:
            return Candidate(self.word, False), None
        return self.fit_effect(context)

    @abstractmethod
    def fit_effect(self, context: Context) -> Trial:
        """As :meth:`Detector.fit`, on a model that lacks the effect (or has it, to refit)."""

    def fit_one_parameter(self, context: Context, effect: Callable[[float], Effect],
                          parameter: str, bounds: tuple[float, float], finding: str,
                          log: bool = False) -> Trial:
        """Fit an effect of one parameter in ``bounds`` and score it (for :meth:`fit_effect`)."""
        def model_with(value: float) -> JointModel:
            return context.model.with_effect(effect(value))
        value = context.fit_scalar(model_with, bounds, log=log)
        return context.score(self.word, model_with(value), {parameter: value},
                             finding.format(format(value, '.3g')))


def feature_signature(word: str, feature: Feature, model: JointModel, augmented: JointModel,
                      run: Run) -> Signature:
    """
    Return the residual signature of ``word`` drawn against ``feature``.

    Returns: residuals of both models and the feature, aligned sample by sample.
    """
    record, start = run.record, run.start
    # Residual i is the increment from sample start + i to start + i + 1.
    samples = np.arange(start + 1, len(record))
    command = delayed_at(record.v, samples, model.delay_samples(run.dt))
    before = velocity_residuals(model, [run])[0]
    after = velocity_residuals(augmented, [run])[0]
    x = None
    triggers = np.zeros(0, dtype=np.int64)
    signs = np.zeros(0)
    if feature == 'command':
        x = command
    elif feature == 'angle':
        x = record.y[start:-1]
    elif feature == 'others':
        summed = summed_other_speeds(run.exogenous, start)
        x = np.zeros(samples.size) if summed is None else summed
    elif feature == 'events':
        triggers = np.flatnonzero(np.diff(command)) + 1
        signs = np.sign(np.diff(command)[triggers - 1])
    else:
        speed = speed_profile(model, record.v, run.dt, v_before=float(record.v[0]))
        direction = np.sign(speed[start + 1:])
        moving = np.flatnonzero(direction != 0)
        triggers = moving[1:][np.diff(direction[moving]) != 0]
        signs = direction[triggers]
    return Signature(word, feature, FEATURE_LABELS[feature], run.dt, before, after, x,
                     triggers, signs)

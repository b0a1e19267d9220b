"""
Whether an effect ``identify`` adds on its own earns its place, on held-out experiments.

The reasoning is in docs/methods.md section 13.8.

"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Sequence

from hydro_sdp.core.arrays import FloatArray
from hydro_sdp.core.errors import HydroSdpError
from hydro_sdp.core.identification.experiment import Experiment
from hydro_sdp.core.identification.held_out import judge, Judgement
from hydro_sdp.core.model.joint_model import JointModel
from hydro_sdp.core.model.simulation import simulate
from hydro_sdp.core.model.timing import SamplePeriod
import numpy as np

#: Fits a model to the training experiments of a fold (None: the effect cannot be fitted).
Fitter = Callable[[Sequence[Experiment]], JointModel | None]


@dataclass(frozen=True)
class HeldOut:
    """
    Held-out errors of a model without and with an effect, judged by the one rule.

    Parameters
    ----------
    effect : str
        The effect's name.
    judgement : Judgement
        The candidates ``without`` and the effect, fold by fold.

    """

    effect: str
    judgement: Judgement

    @property
    def without(self) -> float:
        """Return the pooled held-out error without the effect, degrees."""
        return self.judgement.pooled[0] if self.judgement.weights else 0.0

    @property
    def with_effect(self) -> float:
        """Return the pooled held-out error with the effect, degrees."""
        return self.judgement.pooled[1] if self.judgement.weights else 0.0

    @property
    def gain(self) -> float:
        """Share of the held-out error the effect takes away (negative: it adds error)."""
        return self.judgement.gain(1) if self.judgement.weights else 0.0

    @property
    def kept(self) -> bool:
        """Whether the one rule chooses the model with the effect."""
        return self.judgement.chosen == 1

    def describe(self) -> str:
        """One line for reports: the errors, the band and the verdict."""
        if not self.judgement.weights:
            return f'{self.effect}: nothing held out to judge it on, left out'
        verdict = 'kept' if self.kept else 'left out'
        folds = len(self.judgement.weights)
        return (f'{self.effect}: held-out error {self.without:.4g} -> {self.with_effect:.4g} '
                f'deg ({100.0 * self.gain:+.1f} %, lower on {self.judgement.lower_on(1)} of '
                f'{folds} folds; tie band {self.judgement.bands[0]:.3g} deg), {verdict}')


def simulation_errors(model: JointModel, experiments: Sequence[Experiment],
                      dt: SamplePeriod) -> tuple[float, int]:
    """Sum of absolute simulation errors of a model over experiments, and their sample count."""
    total, count = 0.0, 0
    for experiment in experiments:
        simulated = simulate(model, experiment.v, dt, float(experiment.y[experiment.start]),
                             v_before=float(experiment.v[0]), start=experiment.start)
        residual = experiment.y[experiment.start + 1:] - simulated[experiment.start + 1:]
        total += float(np.sum(np.abs(residual)))
        count += residual.size
    return total, count


def compared(effect: str, rows: Sequence[tuple[float, float]],
             weights: Sequence[float]) -> HeldOut:
    """Return the judgement of a model without and with ``effect`` from per-fold errors."""
    return HeldOut(effect, judge(('without', effect), rows, weights))


def held_out(effect: str, parts: Sequence[tuple[list[Experiment], list[Experiment]]],
             without: Fitter, with_effect: Fitter, dt: SamplePeriod) -> HeldOut:
    """
    Compare a model without and with an effect on the experiments of every fold's test part.

    ``effect``: the effect's name, for reports.
    ``without``, ``with_effect``: fit the model without and with the effect to a training part; a
    fit that fails or returns None for the effect counts as no effect on that fold.
    ``dt``: sample period, s.
    """
    rows, weights = [], []
    for train, test in parts:
        try:
            plain = without(train)
        except HydroSdpError:
            continue
        if plain is None:
            continue
        try:
            shaped = with_effect(train)
        except HydroSdpError:
            shaped = None
        before, samples = simulation_errors(plain, test, dt)
        after = before if shaped is None else simulation_errors(shaped, test, dt)[0]
        if samples == 0:
            continue
        rows.append((before / samples, after / samples))
        weights.append(float(samples))
    return compared(effect, rows, weights)


def at_stop(previous: FloatArray, speed: FloatArray,
            stops: tuple[float | None, float | None], reach: float) -> np.ndarray:
    """
    Mark the samples where the joint sits at an end stop while the command drives it into it.

    ``previous``: angle before each sample, degrees.
    ``speed``: the model's speed over each sample (its sign is the direction driven), deg/s.
    ``stops``: lower and upper stop, degrees; where one is None, the extreme angle of ``previous``
    on that side stands for it (a stop lies at the end of the travel).
    ``reach``: how near the stop counts as at it, degrees.
    Returns: boolean mask, one entry per sample.
    """
    previous = np.asarray(previous, dtype=np.float64)
    speed = np.asarray(speed, dtype=np.float64)
    if previous.size == 0:
        return np.zeros(0, dtype=bool)
    low = float(np.min(previous)) if stops[0] is None else float(stops[0])
    high = float(np.max(previous)) if stops[1] is None else float(stops[1])
    return (((speed < 0.0) & (previous <= low + reach))
            | ((speed > 0.0) & (previous >= high - reach)))

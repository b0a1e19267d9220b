"""
Whether an effect ``identify`` adds on its own earns its place, on held-out experiments.

``identify`` proposes two effects by itself: a first-order ``valve_lag`` found
with the dead time, and a ``stroke_geometry`` factor when the runs span the
stroke. Either fits *something* on any data: a lag soaks up the timing scatter
of commands received between samples, a stroke factor bends to whatever is
left at the ends of the travel. So each is kept only when it predicts
experiments it was not fitted on better, by a clear margin (docs/methods.md
section 4.6): over the folds of :func:`~.family_choice.folds` (whose test parts
never ask the fit to extrapolate), the model with the effect, fitted on the
training part, must lower the pooled error of the test parts by a margin
(:data:`HELD_OUT_GAIN` of the simulation error for the stroke factor,
:data:`INCREMENT_GAIN` of the error of the increments around command changes
for the lag) and lower it on more than half of the folds (one level left out
may still be predicted worse: full-stroke runs hold each duty once).

Neither is fitted on samples where the joint sits at an end stop (:func:`at_stop`):
there the command drives the joint and the joint cannot move, which says
nothing of the valve or the linkage and would read as a slow valve or a slow
end of the stroke.

"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Sequence

from hydro_sdp.core.arrays import FloatArray
from hydro_sdp.core.errors import HydroSdpError
from hydro_sdp.core.identification.experiment import Experiment
from hydro_sdp.core.model.joint_model import JointModel
from hydro_sdp.core.model.simulation import simulate
import numpy as np

#: Share of the held-out simulation error an effect must take away to be kept.
HELD_OUT_GAIN = 0.1
#: The same for errors of the increments around command changes (a lag's check): twice
#: the sensor noise's variance is in every increment and no timing removes it, so a lag
#: that halves the rest shows as a few percent.
INCREMENT_GAIN = 0.05

#: Fits a model to the training experiments of a fold (None: the effect cannot be fitted).
Fitter = Callable[[Sequence[Experiment]], JointModel | None]


@dataclass(frozen=True)
class HeldOut:
    """
    Held-out simulation errors of a model without and with an effect.

    Parameters
    ----------
    effect : str
        The effect's name.
    without, with_effect : float
        Mean absolute simulation error pooled over the test parts, degrees.
    folds : tuple[tuple[float, float], ...]
        Per fold, the two errors.
    margin : float
        Share of the error the effect must take away (:data:`HELD_OUT_GAIN`).

    """

    effect: str
    without: float
    with_effect: float
    folds: tuple[tuple[float, float], ...]
    margin: float = HELD_OUT_GAIN

    @property
    def gain(self) -> float:
        """Share of the held-out error the effect takes away (negative: it adds error)."""
        return 1.0 - self.with_effect / self.without if self.without > 0.0 else 0.0

    @property
    def kept(self) -> bool:
        """
        Whether the effect lowers the pooled error by :attr:`margin`, and most folds clearly.

        Clearly: by half the margin at least. One fold much improved must not carry the
        pooled figure alone (an effect that fixes what a few experiments share, such as
        the transients at the angle where the recording started, is no property of the
        joint).
        """
        clearly = sum(after < (1.0 - 0.5 * self.margin) * before for before, after in self.folds)
        return self.gain >= self.margin and 2 * clearly > len(self.folds)

    def describe(self) -> str:
        """One line for reports."""
        verdict = 'kept' if self.kept else 'left out'
        return (f'{self.effect}: held-out error {self.without:.4g} -> {self.with_effect:.4g} deg '
                f'({100.0 * self.gain:+.1f} %), {verdict}')


def simulation_errors(model: JointModel, experiments: Sequence[Experiment],
                      dt: float) -> tuple[float, int]:
    """
    Sum of absolute simulation errors of a model over experiments, and their sample count.

    Each experiment is simulated from its measured angle at its start, with its
    command history before; the lag starts in steady state at the first command.
    """
    total, count = 0.0, 0
    for experiment in experiments:
        simulated = simulate(model, experiment.v, dt, float(experiment.y[experiment.start]),
                             v_before=float(experiment.v[0]), start=experiment.start)
        residual = experiment.y[experiment.start + 1:] - simulated[experiment.start + 1:]
        total += float(np.sum(np.abs(residual)))
        count += residual.size
    return total, count


def held_out(effect: str, parts: Sequence[tuple[list[Experiment], list[Experiment]]],
             without: Fitter, with_effect: Fitter, dt: float) -> HeldOut:
    """
    Compare a model without and with an effect on the test part of every fold.

    Parameters
    ----------
    effect : str
        The effect's name, for reports.
    parts : sequence of (train, test)
        Folds (:func:`~.family_choice.folds`).
    without, with_effect : callable
        Fit the model without and with the effect to a training part; a fit that
        fails or returns None for the effect counts as no effect on that fold.
    dt : float
        Sample period, s.

    Returns
    -------
    HeldOut
        Pooled and per-fold errors.

    """
    pooled = np.zeros(2)
    count = 0
    per_fold = []
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
        pooled += (before, after)
        count += samples
        per_fold.append((before / samples, after / samples))
    if count == 0:
        return HeldOut(effect, 0.0, 0.0, ())
    return HeldOut(effect, float(pooled[0] / count), float(pooled[1] / count), tuple(per_fold))


def at_stop(previous: FloatArray, speed: FloatArray,
            stops: tuple[float | None, float | None], reach: float) -> np.ndarray:
    """
    Mark the samples where the joint sits at an end stop while the command drives it into it.

    Parameters
    ----------
    previous : FloatArray
        Angle before each sample, degrees.
    speed : FloatArray
        The model's speed over each sample (its sign is the direction driven), deg/s.
    stops : tuple[float | None, float | None]
        Lower and upper stop, degrees; where one is None, the extreme angle of
        ``previous`` on that side stands for it (a stop lies at the end of the travel).
    reach : float
        How near the stop counts as at it, degrees.

    Returns
    -------
    numpy.ndarray
        Boolean mask, one entry per sample.

    """
    previous = np.asarray(previous, dtype=np.float64)
    speed = np.asarray(speed, dtype=np.float64)
    if previous.size == 0:
        return np.zeros(0, dtype=bool)
    low = float(np.min(previous)) if stops[0] is None else float(stops[0])
    high = float(np.max(previous)) if stops[1] is None else float(stops[1])
    return (((speed < 0.0) & (previous <= low + reach))
            | ((speed > 0.0) & (previous >= high - reach)))

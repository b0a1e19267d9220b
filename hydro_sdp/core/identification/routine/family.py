"""
Choosing the map family of routine operation on held-out stretches of it.

The runs are cut into pieces of :data:`PIECE_SECONDS`, dealt out to
:data:`FOLDS` folds in turn, so that every fold trains on stretches from the
whole recording (a closed loop visits its large commands only during its few
large moves; a fold of one contiguous block would hold them out). Each family
is fitted to the increments of the training pieces and scored, as for
experiments, by the simulation error of the held-out pieces, each simulated
from its measured angle: an error of the map accumulates there, where in
one-step increments it hides under the noise. A held-out piece whose commands
reach beyond those its fold trained on is not scored: no fold extrapolates.

A short routine session holds few independent stretches, and which family
wins a fold varies from fold to fold. Another family therefore replaces the
first paper's ``sdp`` only when it predicts better on every fold; among the
families that do, :func:`hydro_sdp.core.identification.family_choice.choose_kind`
chooses as for experiments.

"""

from __future__ import annotations

from dataclasses import dataclass
import math
from typing import Sequence

from hydro_sdp.core.errors import HydroSdpError
from hydro_sdp.core.identification.delay import LevelSpeed
from hydro_sdp.core.identification.experiment import Experiment, split_long
from hydro_sdp.core.identification.family_choice import (
    choose_kind, FittedKind, FoldErrors, KindScore)
from hydro_sdp.core.identification.map_fit import FitData
from hydro_sdp.core.identification.routine.increment_fit import (
    fit_increments, fit_sdp_increments)
from hydro_sdp.core.identification.routine.increments import increments_of
from hydro_sdp.core.model.static_maps import StaticMap
import numpy as np

#: Length of the held-out pieces, s, and the number of folds they are dealt to.
PIECE_SECONDS = 1.0
FOLDS = 4


def routine_pieces(experiments: Sequence[Experiment], dt: float,
                   history: int) -> list[Experiment]:
    """Cut runs into pieces of :data:`PIECE_SECONDS`, each with ``history`` commands before."""
    return split_long(experiments, max(int(round(PIECE_SECONDS / dt)), 1), history)


def _within(piece: Experiment, delay: int, low: float, high: float) -> bool:
    command = increments_of([piece], delay).command
    return bool(np.min(command) >= low and np.max(command) <= high)


@dataclass(frozen=True)
class RoutineScores:
    """
    Held-out errors of the families: the mean, and fold by fold.

    Parameters
    ----------
    scores : tuple[KindScore, ...]
        Mean held-out simulation MAE of each family.
    folds : dict
        Each family's MAE on each fold, degrees.

    """

    scores: tuple[KindScore, ...]
    folds: dict[str, list[float]]

    def __add__(self, other: RoutineScores) -> RoutineScores:
        """Return the scores of both comparisons."""
        return RoutineScores(self.scores + other.scores, {**self.folds, **other.folds})

    def choose(self) -> FittedKind:
        """Return ``sdp`` unless another family predicts better on every fold (then the best)."""
        sdp = self.folds.get('sdp', [])
        if not sdp or not any(s.kind == 'sdp' and math.isfinite(s.mae) for s in self.scores):
            return choose_kind(self.scores)
        eligible = [s for s in self.scores if s.kind == 'sdp' or (
            len(self.folds.get(s.kind, [])) == len(sdp)
            and all(a < b for a, b in zip(self.folds[s.kind], sdp)))]
        return choose_kind(eligible)


def compare_routine_kinds(pieces: Sequence[Experiment], delay: int, dt: float, rest: float,
                          points: Sequence[LevelSpeed],
                          kinds: Sequence[FittedKind]) -> RoutineScores:
    """
    Held-out simulation error of each map family fitted to the increments.

    Parameters
    ----------
    pieces : sequence of Experiment
        Pieces of the runs (:func:`routine_pieces`).
    delay : int
        Delay, samples.
    dt : float
        Sample period, s.
    rest : float
        Rest command.
    points : sequence of LevelSpeed
        Speeds along the command of all the data (starting values).
    kinds : sequence of str
        Families to compare.

    Returns
    -------
    RoutineScores
        The mean over folds of each family's held-out simulation MAE (NaN with the
        reason when it could not be fitted), and its value on each fold.

    """
    tally = FoldErrors(kinds)
    folds = min(FOLDS, len(pieces))
    for fold in range(folds):
        test = list(pieces[fold::folds])
        train = [piece for index, piece in enumerate(pieces) if index % folds != fold]
        if not test or not train:
            continue
        data = increments_of(train, delay)
        low, high = float(np.min(data.command)), float(np.max(data.command))
        inside = [piece for piece in test if _within(piece, delay, low, high)]
        if not inside:
            continue
        held_out = FitData(inside, delay, dt)
        try:
            start = fit_sdp_increments(data, dt, points, rest).static_map
        except HydroSdpError as error:
            tally.fail(error)
            break

        def fit_map(kind: FittedKind) -> StaticMap:
            return start if kind == 'sdp' else fit_increments(
                kind, data, dt, points, rest, start).static_map
        tally.add_fold(held_out, fit_map)
    return RoutineScores(tuple(tally.scores()), tally.fold_errors())

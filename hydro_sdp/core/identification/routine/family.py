"""Choosing the map family of routine operation on held-out stretches of it (methods 15.6)."""

from __future__ import annotations

from typing import Sequence

from hydro_sdp.core.errors import HydroSdpError
from hydro_sdp.core.identification.delay import LevelSpeed
from hydro_sdp.core.identification.experiment import Experiment, split_long
from hydro_sdp.core.identification.family_choice import FittedKind, FoldErrors
from hydro_sdp.core.identification.held_out import deal, Unit
from hydro_sdp.core.identification.map_fit import FitData
from hydro_sdp.core.identification.routine.increment_fit import (
    fit_increments, fit_sdp_increments)
from hydro_sdp.core.identification.routine.increments import increments_of
from hydro_sdp.core.model.static_maps import StaticMap
from hydro_sdp.core.model.timing import SamplePeriod
import numpy as np

#: Length of the held-out pieces, s, and the number of folds they are dealt to.
PIECE_SECONDS = 1.0
FOLDS = 4


def routine_pieces(experiments: Sequence[Experiment], dt: SamplePeriod,
                   history: int) -> list[Experiment]:
    """Cut runs into pieces of :data:`PIECE_SECONDS`, each with ``history`` commands before."""
    return split_long(experiments, max(int(round(PIECE_SECONDS / dt)), 1), history)


def _within(piece: Experiment, delay: int, low: float, high: float) -> bool:
    command = increments_of([piece], delay).command
    return bool(np.min(command) >= low and np.max(command) <= high)


def compare_routine_kinds(pieces: Sequence[Experiment], delay: int, dt: SamplePeriod, rest: float,
                          points: Sequence[LevelSpeed],
                          kinds: Sequence[FittedKind]) -> FoldErrors:
    """
    Held-out simulation error of each map family fitted to the increments.

    ``dt``: sample period, s.
    ``points``: speeds along the command of all the data (starting values).
    Returns: each family's held-out simulation error on each fold (the reason where it could not be
    fitted).
    """
    tally = FoldErrors(kinds)
    units = [Unit(index) for index in range(len(pieces))]
    for train_index, test_index in deal(units, min(FOLDS, len(pieces))):
        train = [pieces[i] for i in train_index]
        test = [pieces[i] for i in test_index]
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
    return tally

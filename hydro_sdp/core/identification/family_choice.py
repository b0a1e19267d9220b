"""The map families, and choosing one on held-out experiments (docs/methods.md section 13.4)."""

from __future__ import annotations

from dataclasses import dataclass
import math
from typing import Callable, cast, get_args, Literal, Sequence

from hydro_sdp.core.errors import DataError, HydroSdpError
from hydro_sdp.core.identification.delay import level_speeds, LevelSpeed
from hydro_sdp.core.identification.experiment import Experiment
from hydro_sdp.core.identification.held_out import deal, judge, Judgement, Unit
from hydro_sdp.core.identification.map_fit import (
    fit_poly, fit_pwl, fit_sdp, FitData, FitMethod, MapFit)
from hydro_sdp.core.identification.map_fit.power_sat import fit_power_sat
from hydro_sdp.core.model.static_maps import SdpMap, StaticMap
from hydro_sdp.core.model.timing import SamplePeriod
import numpy as np

#: Map families ``identify`` can fit, and the choice among them.
FittedKind = Literal['sdp', 'pwl', 'poly', 'power_sat']
KindChoice = Literal[FittedKind, 'auto']
KINDS: tuple[FittedKind, ...] = get_args(FittedKind)
#: Families ``auto`` compares first; ``power_sat`` joins them when ``sdp`` loses.
FIRST_KINDS: tuple[FittedKind, ...] = ('sdp', 'pwl', 'poly')
#: The families from the fewest parameters to the most: the one rule prefers the first
#: of those within their tie band (:func:`~.held_out.judge`).
SIMPLER_FIRST: tuple[FittedKind, ...] = ('sdp', 'power_sat', 'poly', 'pwl')


def _key(experiment: Experiment) -> tuple[str, float, int, float]:
    return (experiment.source, experiment.t0, experiment.y.size, float(np.sum(experiment.y)))


def folds(experiments: Sequence[Experiment], rest: float
          ) -> list[tuple[list[Experiment], list[Experiment]]]:
    """
    Training and test parts of each fold (:func:`~.held_out.deal`).

    Returns: two or more folds; no test level outside its training part's levels on its side.
    """
    ordered = sorted(experiments, key=_key)
    units, runs = [], 0
    for experiment in ordered:
        if experiment.kind == 'step' and math.isfinite(experiment.level):
            units.append(Unit(id(experiment), experiment.level,
                              int(np.sign(experiment.level - rest))))
        else:
            units.append(Unit(('run', runs // 2)))
            runs += 1
    out = [([ordered[i] for i in train], [ordered[i] for i in test])
           for train, test in deal(units)]
    return out if out else _halves(ordered)


def _halves(experiments: Sequence[Experiment]) -> list[tuple[list[Experiment], list[Experiment]]]:
    # Too few experiments to deal out: split each in two halves in time.
    first, second = [], []
    for experiment in experiments:
        middle = experiment.start + experiment.samples // 2
        first.append(Experiment(experiment.v[:middle + 1], experiment.y[:middle + 1],
                                experiment.start, experiment.kind, experiment.level,
                                experiment.t0, experiment.source))
        second.append(Experiment(experiment.v, experiment.y, middle, experiment.kind,
                                 experiment.level, experiment.t0, experiment.source))
    return [(first, second), (second, first)]


@dataclass(frozen=True)
class KindScore:
    """
    Held-out simulation error of one map family.

    Attributes
    ----------
    kind : str
        Map family (one of :data:`KINDS`).
    mae : float
        Mean absolute simulation error over the held-out experiments, pooled over the folds,
        degrees (NaN if it could not be fitted).

    """

    kind: FittedKind
    mae: float
    note: str = ''


class FoldErrors:
    """Each family's held-out errors, fold by fold, and why any failed."""

    def __init__(self, kinds: Sequence[FittedKind]) -> None:
        self.kinds = tuple(kinds)
        self.errors: dict[str, list[float]] = {kind: [] for kind in kinds}
        self.weights: list[float] = []
        self.notes: dict[str, str] = {}

    def fail(self, error: HydroSdpError) -> None:
        """Note that the fit every family starts from failed: none can be scored."""
        self.notes.update({kind: str(error) for kind in self.kinds})

    def add_fold(self, held_out: FitData, fit_map: Callable[[FittedKind], StaticMap]) -> None:
        """Add the error on ``held_out`` of each family still scored, fitted by ``fit_map``."""
        self.weights.append(float(held_out.samples))
        for kind in self.kinds:
            if kind in self.notes:
                continue
            try:
                self.errors[kind].append(held_out.simulation_mae(fit_map(kind).rate))
            except HydroSdpError as error:
                self.notes[kind] = str(error)

    def merged(self, other: FoldErrors) -> FoldErrors:
        """Return the errors of both comparisons, made on the same folds."""
        both = FoldErrors(self.kinds + other.kinds)
        both.errors = {**self.errors, **other.errors}
        both.weights = self.weights or other.weights
        both.notes = {**self.notes, **other.notes}
        return both

    def judgement(self) -> Judgement:
        """Return the families judged by the one rule, simplest first (:data:`SIMPLER_FIRST`)."""
        kinds = sorted(self.kinds, key=SIMPLER_FIRST.index)
        columns = [self.errors[kind] if kind not in self.notes
                   and len(self.errors[kind]) == len(self.weights)
                   else [math.nan] * len(self.weights) for kind in kinds]
        return judge(kinds, list(zip(*columns)) if self.weights else [], self.weights)

    def scores(self) -> list[KindScore]:
        """Return each family's pooled error (NaN, with the note, if it failed)."""
        pooled = dict(zip(self.judgement().names, self.judgement().pooled))
        return [KindScore(kind, pooled.get(kind, math.nan), self.notes.get(kind, ''))
                for kind in self.kinds]

    def chosen(self) -> FittedKind:
        """Return the family the one rule chooses, or raise naming why none could be fitted."""
        judgement = self.judgement()
        if judgement.chosen < 0:
            raise DataError('no map family could be fitted: ' +
                            '; '.join(f'{s.kind}: {s.note}' for s in self.scores()))
        return cast(FittedKind, judgement.names[judgement.chosen])


def fit_family(kind: FittedKind, data: FitData, points: Sequence[LevelSpeed], rest: float,
               method: FitMethod, sdp_map: SdpMap | None, starts: int = 4) -> MapFit[StaticMap]:
    """
    Fit one map family to experiments.

    ``kind``: the family (one of :data:`KINDS`).
    ``points``: speed of every experiment and command level (the starting values).
    ``sdp_map``: the ``sdp`` fit the others start from (its dead-zone), if already made.
    """
    if kind == 'sdp':
        return fit_sdp(data, points, rest, method=method, starts=starts)
    if kind == 'poly':
        # The second paper's fit to the points, refined on the angles by the method asked.
        return fit_poly(points, rest, data=data, method=method)
    if sdp_map is None:
        sdp_map = fit_sdp(data, points, rest, method='rr', starts=1).static_map
    if kind == 'pwl':
        return fit_pwl(data, points, rest, sdp_map.dead_zone, method=method)
    return fit_power_sat(data, points, rest, sdp_map, method=method)


@dataclass(frozen=True, eq=False)
class Fold:
    """
    One fold's experiments arranged for fitting, and the ``sdp`` fit every family starts from.

    Attributes
    ----------
    points : list of LevelSpeed
        The training part's per-level speeds.
    sdp_map : SdpMap
        The ``sdp`` map fitted on the training part.

    """

    data: FitData
    held_out: FitData
    points: list[LevelSpeed]
    sdp_map: SdpMap


class FoldFits:
    """
    The folds of :func:`folds` with their ``sdp`` fits, made once for every comparison.

    ``dt``: sample period, s.
    ``lag``: valve lag time constant, s.
    """

    def __init__(self, experiments: Sequence[Experiment], delay: int, dt: SamplePeriod,
                 rest: float, method: FitMethod, lag: float = 0.0) -> None:
        self.rest = rest
        self.dt = dt
        self.method = method
        self.folds: list[Fold] = []
        #: Why a fold's ``sdp`` fit failed (then no family can be scored), if one did.
        self.error: HydroSdpError | None = None
        for train, test in folds(experiments, rest):
            data = FitData(train, delay, dt, lag)
            try:
                points = level_speeds(train, delay, dt, rest=rest)
                sdp_map = fit_sdp(data, points, rest, method=method, starts=2).static_map
            except HydroSdpError as error:
                self.error = error
                break
            self.folds.append(Fold(data, FitData(test, delay, dt, lag), points, sdp_map))


def compare_kinds(experiments: Sequence[Experiment], delay: int, dt: SamplePeriod, rest: float,
                  method: FitMethod, kinds: Sequence[FittedKind] = KINDS,
                  dead_zone: tuple[float, float] | None = None,
                  lag: float = 0.0, fold_fits: FoldFits | None = None) -> FoldErrors:
    """
    Held-out error of each map family, over folds that never extrapolate.

    ``dt``: sample period, s.
    ``dead_zone``: plateau of the ``pwl`` map (default: from the ``sdp`` fit of each fold).
    ``lag``: valve lag time constant, s.
    ``fold_fits``: the folds and their ``sdp`` fits, made for these same arguments (default: made
    here).
    Returns: each family's mean absolute simulation error over each fold's test part.
    """
    if fold_fits is None:
        fold_fits = FoldFits(experiments, delay, dt, rest, method, lag)
    tally = FoldErrors(kinds)
    for fold in fold_fits.folds:
        def fit_map(kind: FittedKind, fold: Fold = fold) -> StaticMap:
            if kind == 'sdp':
                return fold.sdp_map
            start = fold.sdp_map if dead_zone is None else SdpMap(
                dead_zone, fold.sdp_map.saturation_velocity, fold.sdp_map.curvature)
            return fit_family(kind, fold.data, fold.points, rest, method, start,
                              starts=2).static_map
        tally.add_fold(fold.held_out, fit_map)
    if fold_fits.error is not None:
        tally.fail(fold_fits.error)
    return tally

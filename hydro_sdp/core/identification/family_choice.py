"""
The map families, and choosing one on held-out experiments with folds that never extrapolate.

A held-out score is fair only when every fold's training part spans the
commands its test part holds: both directions, and the levels on either side.
Step experiments are stratified by direction and level: a level held several
times is dealt out over the folds; a level held once (full-stroke runs at one
duty each) is left out in turn only when it lies strictly inside its
direction's range, so the fit interpolates it (leave-one-level-out), and the
outermost levels always train. Runs of changing commands, whose levels
spread over the range anyway, alternate between the folds in pairs.

"""

from __future__ import annotations

from collections import defaultdict
from dataclasses import dataclass
import math
from typing import Callable, get_args, Literal, Sequence

from hydro_sdp.core.errors import DataError, HydroSdpError
from hydro_sdp.core.identification.delay import level_speeds, LevelSpeed
from hydro_sdp.core.identification.experiment import Experiment
from hydro_sdp.core.identification.map_fit import (
    fit_poly, fit_pwl, fit_sdp, FitData, FitMethod, MapFit)
from hydro_sdp.core.identification.map_fit.power_sat import fit_power_sat
from hydro_sdp.core.model.static_maps import SdpMap, StaticMap
import numpy as np

#: Map families ``identify`` can fit, and the choice among them.
FittedKind = Literal['sdp', 'pwl', 'poly', 'power_sat']
KindChoice = Literal[FittedKind, 'auto']
KINDS: tuple[FittedKind, ...] = get_args(FittedKind)
#: Families ``auto`` compares first; ``power_sat`` joins them when ``sdp`` loses.
FIRST_KINDS: tuple[FittedKind, ...] = ('sdp', 'pwl', 'poly')
#: ``auto`` keeps ``sdp`` when its held-out error is within this factor of the best.
PARSIMONY = 1.05
#: Families of a physical shape, and the factor a free-form family must beat them by.
SMOOTH_KINDS = ('sdp', 'power_sat')
FREE_FORM_MARGIN = 1.5
#: Most folds of the leave-one-level-out scheme.
MAX_FOLDS = 4


def _key(experiment: Experiment) -> tuple[str, float, int, float]:
    return (experiment.source, experiment.t0, experiment.y.size, float(np.sum(experiment.y)))


def folds(experiments: Sequence[Experiment], rest: float
          ) -> list[tuple[list[Experiment], list[Experiment]]]:
    """
    Training and test parts of each fold.

    Parameters
    ----------
    experiments : sequence of Experiment
        All experiments.
    rest : float
        Rest command (splits the directions).

    Returns
    -------
    list of (train, test)
        Two or more folds; every test part non-empty, no test level outside the
        range of its training part's levels on the same side of rest.

    """
    ordered = sorted(experiments, key=_key)
    steps = [e for e in ordered if e.kind == 'step' and math.isfinite(e.level)]
    runs = [e for e in ordered if not (e.kind == 'step' and math.isfinite(e.level))]
    strata: dict[float, list[Experiment]] = defaultdict(list)
    for experiment in steps:
        strata[experiment.level].append(experiment)
    repeated = {level: members for level, members in strata.items() if len(members) >= 2}
    single = sorted(level for level, members in strata.items() if len(members) == 1)
    interior: list[list[float]] = []
    for sign in (-1.0, 1.0):
        side = sorted((level for level in strata if sign * (level - rest) > 0),
                      key=lambda level: abs(level - rest))
        inner = set(side[1:-1])
        interior.append([level for level in single if level in inner])
    count = max(2, min(MAX_FOLDS, max(len(levels) for levels in interior)))
    assignment: dict[int, int] = {}
    for members in repeated.values():
        for index, experiment in enumerate(members):
            assignment[id(experiment)] = index % count
    for levels in interior:
        for index, level in enumerate(levels):
            assignment[id(strata[level][0])] = index % count
    for index, experiment in enumerate(runs):
        assignment[id(experiment)] = index // 2 % count
    out = []
    for fold in range(count):
        test = [e for e in ordered if assignment.get(id(e)) == fold]
        train = [e for e in ordered if assignment.get(id(e)) != fold]
        if test and train:
            out.append((train, test))
    if out:
        return out
    return _halves(ordered)


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

    Parameters
    ----------
    kind : str
        Map family (one of :data:`KINDS`).
    mae : float
        Mean absolute simulation error on held-out experiments, degrees (NaN if it
        could not be fitted).
    note : str
        Why it could not be fitted, if so.

    """

    kind: FittedKind
    mae: float
    note: str = ''


class FoldErrors:
    """
    Each family's held-out simulation errors, fold by fold, and why any failed.

    A failure of the fit every family starts from (:meth:`fail`) ends the
    comparison of all of them; a family's own failure ends that family's.

    Parameters
    ----------
    kinds : sequence of str
        The families compared.

    """

    def __init__(self, kinds: Sequence[FittedKind]) -> None:
        self.kinds = tuple(kinds)
        self.errors: dict[str, list[float]] = {kind: [] for kind in kinds}
        self.notes: dict[str, str] = {}

    def fail(self, error: HydroSdpError) -> None:
        """Note that the fit every family starts from failed: none can be scored."""
        self.notes.update({kind: str(error) for kind in self.kinds})

    def add_fold(self, held_out: FitData, fit_map: Callable[[FittedKind], StaticMap]) -> None:
        """Add the error on ``held_out`` of each family still scored, fitted by ``fit_map``."""
        for kind in self.kinds:
            if kind in self.notes:
                continue
            try:
                self.errors[kind].append(held_out.simulation_mae(fit_map(kind).rate))
            except HydroSdpError as error:
                self.notes[kind] = str(error)

    def scores(self) -> list[KindScore]:
        """Return each family's mean error over the folds (NaN, with the note, if it failed)."""
        return [KindScore(kind, float(np.mean(self.errors[kind]))
                          if kind not in self.notes and self.errors[kind] else math.nan,
                          self.notes.get(kind, '')) for kind in self.kinds]

    def fold_errors(self) -> dict[str, list[float]]:
        """Return the errors fold by fold of the families that were fitted on every fold."""
        return {kind: self.errors[kind] for kind in self.kinds if kind not in self.notes}


def fit_family(kind: FittedKind, data: FitData, points: Sequence[LevelSpeed], rest: float,
               method: FitMethod, sdp_map: SdpMap | None, starts: int = 4) -> MapFit[StaticMap]:
    """
    Fit one map family to experiments.

    Parameters
    ----------
    kind : str
        The family (one of :data:`KINDS`).
    data : FitData
        The experiments arranged for the fit.
    points : sequence of LevelSpeed
        Speed of every experiment and command level (the starting values).
    rest : float
        Rest command.
    method : str
        ``rr`` or ``oe``.
    sdp_map : SdpMap or None
        The ``sdp`` fit the others start from (its dead-zone), if already made.
    starts : int
        Starts of the ``sdp`` multi-start search.

    Returns
    -------
    MapFit
        The fit.

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

    Parameters
    ----------
    data, held_out : FitData
        The training and the test part.
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

    ``identify`` compares the first families, then ``power_sat`` on the same folds:
    both start from these fits.

    Parameters
    ----------
    experiments : sequence of Experiment
        All experiments.
    delay : int
        Delay, samples.
    dt : float
        Sample period, s.
    rest : float
        Rest command.
    method : str
        Fitting method (``rr`` or ``oe``), for every family.
    lag : float
        Valve lag time constant, s.

    """

    def __init__(self, experiments: Sequence[Experiment], delay: int, dt: float, rest: float,
                 method: FitMethod, lag: float = 0.0) -> None:
        self.rest = rest
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


def compare_kinds(experiments: Sequence[Experiment], delay: int, dt: float, rest: float,
                  method: FitMethod, kinds: Sequence[FittedKind] = KINDS,
                  dead_zone: tuple[float, float] | None = None,
                  lag: float = 0.0, fold_fits: FoldFits | None = None) -> list[KindScore]:
    """
    Held-out simulation error of each map family, over folds that never extrapolate.

    Parameters
    ----------
    experiments : sequence of Experiment
        All experiments.
    delay : int
        Delay, samples.
    dt : float
        Sample period, s.
    rest : float
        Rest command.
    method : str
        Fitting method (``rr`` or ``oe``), for every family.
    kinds : sequence of str
        Families to compare.
    dead_zone : tuple[float, float] or None
        Plateau of the ``pwl`` map (default: from the ``sdp`` fit of each fold).
    lag : float
        Valve lag time constant, s.
    fold_fits : FoldFits or None
        The folds and their ``sdp`` fits, made for these same arguments (default:
        made here).

    Returns
    -------
    list of KindScore
        One score per family: the mean over folds of the held-out MAE.

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
    return tally.scores()


def choose_kind(scores: Sequence[KindScore]) -> FittedKind:
    """
    Pick the family with the least held-out error, preferring the smooth families.

    ``sdp`` is kept when it is within :data:`PARSIMONY` of the best smooth
    family (``sdp``, ``power_sat``), and a smooth family within
    :data:`FREE_FORM_MARGIN` of a free-form one (``pwl``, ``poly``): folds can
    only leave out levels between measured ones, where an interpolant is at its
    best, so a free-form shape must win clearly.
    """
    usable = [s for s in scores if math.isfinite(s.mae)]
    if not usable:
        raise DataError('no map family could be fitted: ' +
                        '; '.join(f'{s.kind}: {s.note}' for s in scores))
    best = min(usable, key=lambda s: s.mae)
    smooth = [s for s in usable if s.kind in SMOOTH_KINDS]
    if not smooth:
        return best.kind
    best_smooth = min(smooth, key=lambda s: s.mae)
    sdp = next((s for s in smooth if s.kind == 'sdp'), None)
    if sdp is not None and sdp.mae <= PARSIMONY * best_smooth.mae:
        best_smooth = sdp
    margin = PARSIMONY if best_smooth.kind == 'sdp' else FREE_FORM_MARGIN
    return best_smooth.kind if best_smooth.mae <= margin * best.mae else best.kind

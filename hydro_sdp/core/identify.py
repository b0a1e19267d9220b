"""
Offline identification of a hydraulic joint from records (the ``identify`` command).

The pipeline of West et al. (2018) section 4, made automatic: cut the records
into experiments, estimate the pure delay, measure the speed of every command
level (their Figs. 2 and 3), then fit the static map to the raw angles by
regret-regression (or their output-error fit). Besides eq. (5) (``sdp``), a
monotone piecewise-linear map (``pwl``) and the second paper's polynomial gain
(``poly``) are fitted, and the family that predicts held-out experiments best
is chosen (``kind='auto'``), preferring the simpler ``sdp`` when it is within
5 % of the best. The result is a :class:`~hydro_sdp.core.model.JointModel`.

"""

from __future__ import annotations

from dataclasses import dataclass
import math
from typing import Callable, get_args, Literal, Sequence

from hydro_sdp.core.delay import DelayEstimate, estimate_delay, level_speeds, LevelSpeed
from hydro_sdp.core.errors import DataError, HydroSdpError
from hydro_sdp.core.experiments import (
    check_record, Experiment, segment_records, Segmentation, split_long, thin)
from hydro_sdp.core.map_fit import (
    FIT_METHODS, fit_poly, fit_pwl, fit_sdp, FitData, FitMethod, MapFit)
from hydro_sdp.core.model import JointModel
from hydro_sdp.core.records import Record
from hydro_sdp.core.static_maps import StaticMap
import numpy as np

#: Map families ``identify`` can fit, and the choice among them.
FittedKind = Literal['sdp', 'pwl', 'poly']
KindChoice = Literal[FittedKind, 'auto']
KINDS: tuple[FittedKind, ...] = get_args(FittedKind)
#: Longest piece a fit sees, and the sample budgets of the multi-start search and the
#: delay search: long records are cut and thinned there, and the best start is then
#: refined on all the data.
PIECE_SAMPLES = 3000
SEARCH_SAMPLES = 60_000
DELAY_SAMPLES = 100_000
#: ``auto`` keeps ``sdp`` when its held-out error is within this factor of the best.
PARSIMONY = 1.05


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


@dataclass(frozen=True, eq=False)
class Identification:
    """
    Everything ``identify`` found.

    Parameters
    ----------
    model : JointModel
        The identified joint.
    sample_period : float
        Sample period of the records, s.
    delay : DelayEstimate
        The delay and what each estimator found.
    segmentation : Segmentation
        The experiments used and dropped.
    points : tuple[LevelSpeed, ...]
        Speed of every experiment and command level.
    fit : MapFit
        The chosen map's fit.
    comparison : tuple[KindScore, ...]
        Held-out errors of the map families tried.
    mae : float
        Mean absolute simulation error of the model on all experiments, degrees.

    """

    model: JointModel
    sample_period: float
    delay: DelayEstimate
    segmentation: Segmentation
    points: tuple[LevelSpeed, ...]
    fit: MapFit[StaticMap]
    comparison: tuple[KindScore, ...]
    mae: float

    @property
    def alpha(self) -> tuple[float, ...] | None:
        """Return the paper's ``alpha_1..alpha_6`` at the records' sample period (``sdp``)."""
        if self.model.kind != 'sdp':
            return None
        return self.model.alpha(self.sample_period)


def _fit_kind(kind: FittedKind, data: FitData, points: Sequence[LevelSpeed], rest: float,
              method: FitMethod, dead_zone: tuple[float, float] | None,
              starts: int = 4) -> MapFit[StaticMap]:
    if kind == 'sdp':
        return fit_sdp(data, points, rest, method=method, starts=starts)
    if kind == 'pwl':
        if dead_zone is None:
            dead_zone = fit_sdp(data, points, rest, method='rr', starts=1).static_map.dead_zone
        return fit_pwl(data, points, rest, dead_zone)
    return fit_poly(points, rest)


def _folds(experiments: Sequence[Experiment]) -> tuple[list[Experiment], list[Experiment]]:
    ordered = sorted(experiments, key=lambda e: (e.source, e.t0))
    if len(ordered) >= 4:
        # Alternate pairs, not single experiments: step programs alternate in sign, and
        # each fold needs both directions.
        pairs = [index // 2 % 2 for index in range(len(ordered))]
        return ([e for e, fold in zip(ordered, pairs) if fold == 0],
                [e for e, fold in zip(ordered, pairs) if fold == 1])
    # Too few experiments to alternate: split each in two halves in time.
    first, second = [], []
    for experiment in ordered:
        middle = experiment.start + experiment.samples // 2
        first.append(Experiment(experiment.v[:middle + 1], experiment.y[:middle + 1],
                                experiment.start, experiment.kind, experiment.level,
                                experiment.t0, experiment.source))
        second.append(Experiment(experiment.v, experiment.y, middle, experiment.kind,
                                 experiment.level, experiment.t0, experiment.source))
    return first, second


def compare_kinds(experiments: Sequence[Experiment], delay: int, dt: float, rest: float,
                  method: FitMethod, kinds: Sequence[FittedKind] = KINDS,
                  dead_zone: tuple[float, float] | None = None) -> list[KindScore]:
    """
    Two-fold held-out simulation error of each map family.

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
        Fitting method for ``sdp``.
    kinds : sequence of str
        Families to compare.
    dead_zone : tuple[float, float] or None
        Plateau of the ``pwl`` map (default: from an ``sdp`` fit of each fold).

    Returns
    -------
    list of KindScore
        One score per family.

    """
    folds = _folds(experiments)
    scores = []
    for kind in kinds:
        errors = []
        note = ''
        for train, test in ((folds[0], folds[1]), (folds[1], folds[0])):
            try:
                points = level_speeds(train, delay, dt, rest=rest)
                fitted = _fit_kind(kind, FitData(train, delay, dt), points, rest, method,
                                   dead_zone, starts=2)
                errors.append(FitData(test, delay, dt).simulation_mae(fitted.static_map.rate))
            except HydroSdpError as error:
                note = str(error)
                break
        scores.append(KindScore(kind, float(np.mean(errors)) if len(errors) == 2 else math.nan,
                                note))
    return scores


def choose_kind(scores: Sequence[KindScore]) -> FittedKind:
    """Pick the family with the least held-out error, keeping ``sdp`` when it is close."""
    usable = [s for s in scores if math.isfinite(s.mae)]
    if not usable:
        raise DataError('no map family could be fitted: ' +
                        '; '.join(f'{s.kind}: {s.note}' for s in scores))
    best = min(usable, key=lambda s: s.mae)
    sdp = next((s for s in usable if s.kind == 'sdp'), None)
    if sdp is not None and sdp.mae <= PARSIMONY * best.mae:
        return 'sdp'
    return best.kind


def identify(records: Sequence[Record], *, method: FitMethod = 'rr', kind: KindChoice = 'auto',
             max_delay: float = 0.5, angle_limits: tuple[float, float] | None = None,
             input_limits: tuple[float, float] | None = None,
             progress: Callable[[str], None] | None = None) -> Identification:
    """
    Identify a joint model from records of one joint.

    Parameters
    ----------
    records : sequence of Record
        Step experiments and/or random-level runs of one joint, same sample period.
    method : str
        ``rr`` (regret-regression, default) or ``oe`` (West et al.'s output-error fit).
    kind : str
        ``auto``, ``sdp``, ``pwl`` or ``poly``.
    max_delay : float
        Largest delay considered, s.
    angle_limits : tuple[float, float] or None
        Known end stops; default: those seen in the data, if any.
    input_limits : tuple[float, float] or None
        Command range of the valve, written to the model.
    progress : callable or None
        Called with the name of each stage as it starts.

    Returns
    -------
    Identification
        The model and the evidence.

    """
    if kind not in KINDS + ('auto',):
        raise DataError(f"kind must be auto, {', '.join(KINDS)}; got {kind!r}")
    if method not in FIT_METHODS:
        raise DataError(f"method must be 'rr' or 'oe', got {method!r}")
    if not records:
        raise DataError('no records to identify from')
    joints = {record.joint for record in records}
    if len(joints) > 1:
        raise DataError(f"records of several joints ({', '.join(sorted(joints))}); "
                        'identify one joint at a time')
    periods = [check_record(record) for record in records]
    dt = float(np.median(periods))
    if max(periods) > 1.01 * min(periods):
        raise DataError(f'records have different sample periods ({min(periods):.4f} s to '
                        f'{max(periods):.4f} s); resample them first')
    step = (lambda name: progress(name)) if progress is not None else (lambda name: None)
    step('segmenting')
    max_delay_samples = max(2, int(round(max_delay / dt)))
    segmentation = segment_records(records, max_delay=max_delay_samples,
                                   angle_limits=angle_limits)
    if not segmentation.experiments:
        reasons = '; '.join(sorted({d.reason for d in segmentation.dropped})) or 'none found'
        raise DataError(f'no usable experiments ({reasons})')
    step('estimating the delay')
    pieces = split_long(segmentation.experiments, PIECE_SAMPLES, max_delay_samples)
    delay = estimate_delay(thin(pieces, DELAY_SAMPLES), dt, max_delay=max_delay_samples,
                           rest=segmentation.rest, noise=segmentation.noise_std)
    points = tuple(level_speeds(pieces, delay.samples, dt, rest=segmentation.rest))
    data = FitData(pieces, delay.samples, dt)
    sample = thin(pieces, SEARCH_SAMPLES)
    search = data if len(sample) == len(pieces) else FitData(sample, delay.samples, dt)
    step('fitting the static map')
    sdp_fit = fit_sdp(search, points, segmentation.rest, method=method,
                      polish=None if search is data else data)
    comparison: tuple[KindScore, ...] = ()
    chosen: FittedKind = 'sdp' if kind == 'auto' else kind
    if kind == 'auto':
        step('comparing map families on held-out experiments')
        comparison = tuple(compare_kinds(sample, delay.samples, dt, segmentation.rest,
                                         method, dead_zone=sdp_fit.static_map.dead_zone))
        chosen = choose_kind(comparison)
    fit: MapFit[StaticMap] = sdp_fit if chosen == 'sdp' else _fit_kind(
        chosen, data, points, segmentation.rest, method, sdp_fit.static_map.dead_zone)
    limits = angle_limits
    low_stop, high_stop = segmentation.end_stops
    if limits is None and low_stop is not None and high_stop is not None:
        limits = (low_stop, high_stop)
    # Stamps are integer nanoseconds: round the delay there, not at float noise.
    model = JointModel(joint=next(iter(joints)) or 'joint', static_map=fit.static_map,
                       delay=round(delay.samples * dt, 9), angle_limits=limits,
                       input_limits=input_limits)
    return Identification(model, dt, delay, segmentation, points, fit, comparison,
                          data.simulation_mae(fit.static_map.rate))

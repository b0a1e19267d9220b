"""
Offline identification of a hydraulic joint from records (the ``identify`` command).

The pipeline of West et al. (2018) section 4, made automatic: cut the records
into experiments (at the valve's neutral, and where an end stop holds the
joint), estimate the dead time with the valve's first-order lag, measure the
speed of every command level (their Figs. 2 and 3), then fit the static map to
the raw angles by regret-regression (or their output-error fit). Besides eq.
(5) (``sdp``), a monotone piecewise-linear map (``pwl``), the second paper's
polynomial gain (``poly``) and a saturating power law (``power_sat``, convex
from the dead-zone) are fitted, and the family that predicts held-out
experiments best is chosen (``kind='auto'``, folds that never extrapolate:
:mod:`hydro_sdp.core.identification.family_choice`), preferring the simpler ``sdp`` when it is
within 5 % of the best. When the data span the stroke, a ``stroke_geometry``
factor of the angle is fitted on top. The result is a
:class:`~hydro_sdp.core.model.joint_model.JointModel` whose effects carry the lag and the
geometry found.

"""

from __future__ import annotations

from dataclasses import dataclass
import math
from typing import Callable, get_args, Literal, Sequence

from hydro_sdp.core.errors import DataError, HydroSdpError
from hydro_sdp.core.identification.delay import (
    DelayEstimate, estimate_delay, level_speeds, LevelSpeed)
from hydro_sdp.core.identification.effect_check import HeldOut, simulation_errors
from hydro_sdp.core.identification.end_stops import stop_reach
from hydro_sdp.core.identification.family_choice import folds
from hydro_sdp.core.identification.map_fit import (
    FIT_METHODS, fit_poly, fit_pwl, fit_sdp, FitData, FitMethod, MapFit)
from hydro_sdp.core.identification.map_fit.power_sat import fit_power_sat
from hydro_sdp.core.identification.own_effects import (
    check_geometry, check_lag, shape_with_geometry)
from hydro_sdp.core.identification.segmentation import (
    check_record, Experiment, segment_records, Segmentation, split_long, thin)
from hydro_sdp.core.identification.stroke_fit import fit_stroke_geometry
from hydro_sdp.core.model.effects import Effect, ValveLag
from hydro_sdp.core.model.joint_model import JointModel
from hydro_sdp.core.model.records import Record
from hydro_sdp.core.model.sample_period import nominal_period, whole_samples_seconds
from hydro_sdp.core.model.static_maps import SdpMap, StaticMap
import numpy as np

#: Map families ``identify`` can fit, and the choice among them.
FittedKind = Literal['sdp', 'pwl', 'poly', 'power_sat']
KindChoice = Literal[FittedKind, 'auto']
KINDS: tuple[FittedKind, ...] = get_args(FittedKind)
#: Families ``auto`` compares first; ``power_sat`` joins them when ``sdp`` loses.
FIRST_KINDS: tuple[FittedKind, ...] = ('sdp', 'pwl', 'poly')
#: Longest piece a fit sees, and the sample budgets of the multi-start search and the
#: delay search: long records are cut and thinned there, and the best start is then
#: refined on all the data.
PIECE_SAMPLES = 3000
SEARCH_SAMPLES = 60_000
DELAY_SAMPLES = 100_000
#: Sample budget of the held-out comparison of map families: every fold refits every
#: family, and a few hundred experiments score them as well as a thousand.
COMPARE_SAMPLES = 30_000
#: ``auto`` keeps ``sdp`` when its held-out error is within this factor of the best.
PARSIMONY = 1.05
#: Families of a physical shape, and the factor a free-form family must beat them by.
SMOOTH_KINDS = ('sdp', 'power_sat')
FREE_FORM_MARGIN = 1.5


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
    effect_checks : tuple[HeldOut, ...]
        Held-out errors without and with each effect identify proposed by itself
        (``valve_lag``, ``stroke_geometry``), and whether it was kept.

    """

    model: JointModel
    sample_period: float
    delay: DelayEstimate
    segmentation: Segmentation
    points: tuple[LevelSpeed, ...]
    fit: MapFit[StaticMap]
    comparison: tuple[KindScore, ...]
    mae: float
    effect_checks: tuple[HeldOut, ...] = ()

    @property
    def alpha(self) -> tuple[float, ...] | None:
        """Return the paper's ``alpha_1..alpha_6`` at the records' sample period (``sdp``)."""
        if self.model.kind != 'sdp':
            return None
        return self.model.alpha(self.sample_period)


def _fit_kind(kind: FittedKind, data: FitData, points: Sequence[LevelSpeed], rest: float,
              method: FitMethod, sdp_map: SdpMap | None, starts: int = 4) -> MapFit[StaticMap]:
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


def compare_kinds(experiments: Sequence[Experiment], delay: int, dt: float, rest: float,
                  method: FitMethod, kinds: Sequence[FittedKind] = KINDS,
                  dead_zone: tuple[float, float] | None = None,
                  lag: float = 0.0) -> list[KindScore]:
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

    Returns
    -------
    list of KindScore
        One score per family: the mean over folds of the held-out MAE.

    """
    parts = folds(experiments, rest)
    errors: dict[str, list[float]] = {kind: [] for kind in kinds}
    notes: dict[str, str] = {}
    for train, test in parts:
        data = FitData(train, delay, dt, lag)
        held_out = FitData(test, delay, dt, lag)
        try:
            points = level_speeds(train, delay, dt, rest=rest)
            sdp_map: SdpMap | None = fit_sdp(data, points, rest, method=method,
                                             starts=2).static_map
        except HydroSdpError as error:
            notes.update({kind: str(error) for kind in kinds})
            break
        for kind in kinds:
            if kind in notes:
                continue
            try:
                if kind == 'sdp':
                    static_map: StaticMap = sdp_map  # type: ignore[assignment]
                else:
                    start = sdp_map if dead_zone is None or sdp_map is None else SdpMap(
                        dead_zone, sdp_map.saturation_velocity, sdp_map.curvature)
                    static_map = _fit_kind(kind, data, points, rest, method, start,
                                           starts=2).static_map
                errors[kind].append(held_out.simulation_mae(static_map.rate))
            except HydroSdpError as error:
                notes[kind] = str(error)
    return [KindScore(kind, float(np.mean(errors[kind]))
                      if kind not in notes and errors[kind] else math.nan, notes.get(kind, ''))
            for kind in kinds]


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


def experiments_mae(model: JointModel, experiments: Sequence[Experiment], dt: float) -> float:
    """
    Mean absolute simulation error of a model over experiments, degrees (per sample).

    Each experiment is simulated from its measured angle at its start, with its
    command history before; the lag starts in steady state at the first command.
    """
    total, count = simulation_errors(model, experiments, dt)
    return total / max(count, 1)


def thin_evenly(experiments: Sequence[Experiment], max_samples: int,
                rest: float) -> list[Experiment]:
    """
    Keep every k-th experiment of each kind and direction, up to about ``max_samples``.

    Parameters
    ----------
    experiments : sequence of Experiment
        The experiments.
    max_samples : int
        Sample budget (predicted samples).
    rest : float
        Rest command (splits the directions of step experiments).

    Returns
    -------
    list of Experiment
        All of them when within budget, else every k-th of each kind and direction,
        in their order: alternating directions are not thinned to one.

    """
    total = sum(e.samples for e in experiments)
    if total <= max_samples:
        return list(experiments)
    stride = math.ceil(total / max_samples)
    seen: dict[tuple[str, float], int] = {}
    out = []
    for experiment in experiments:
        side = float(np.sign(experiment.level - rest)) if math.isfinite(experiment.level) \
            else 0.0
        group = (experiment.kind, side)
        count = seen.get(group, 0)
        seen[group] = count + 1
        if count % stride == 0:
            out.append(experiment)
    return out


def records_period(records: Sequence[Record]) -> float:
    """
    Return the nominal sample period shared by records, s.

    Each record's nominal period must lie within 1 % of the others'; the result is
    the nominal period of all their spacings together, so records of one timer
    give one period whatever their length.
    """
    periods = [check_record(record) for record in records]
    if max(periods) > 1.01 * min(periods):
        raise DataError(f'records have different sample periods ({min(periods):.4g} s to '
                        f'{max(periods):.4g} s); resample them first')
    return nominal_period(np.concatenate([np.diff(record.t) for record in records]))


def identify(records: Sequence[Record], *, method: FitMethod = 'rr', kind: KindChoice = 'auto',
             max_delay: float = 0.5, angle_limits: tuple[float, float] | None = None,
             input_limits: tuple[float, float] | None = None, rest: float | None = None,
             progress: Callable[[str], None] | None = None) -> Identification:
    """
    Identify a joint model from records of one joint.

    Parameters
    ----------
    records : sequence of Record
        Step experiments, full-stroke runs and/or random-level runs of one joint,
        same sample period (their order does not matter).
    method : str
        ``rr`` (regret-regression, default) or ``oe`` (output error), for every family.
    kind : str
        ``auto``, ``sdp``, ``pwl``, ``poly`` or ``power_sat``.
    max_delay : float
        Largest delay considered, s.
    angle_limits : tuple[float, float] or None
        Known end stops; default: those seen in the data, if any.
    input_limits : tuple[float, float] or None
        Command range of the valve, written to the model (its middle is the
        preferred rest when it excludes 0).
    rest : float or None
        The valve's neutral command; default: 0 when the commands take both
        signs and the joint stands still there, else from the data.
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
    dt = records_period(records)
    step = (lambda name: progress(name)) if progress is not None else (lambda name: None)
    step('segmenting')
    max_delay_samples = max(2, int(round(max_delay / dt)))
    segmentation = segment_records(records, max_delay=max_delay_samples,
                                   angle_limits=angle_limits, rest=rest,
                                   input_limits=input_limits)
    if not segmentation.experiments:
        reasons = '; '.join(sorted({d.reason for d in segmentation.dropped})) or 'none found'
        raise DataError(f'no usable experiments ({reasons})')
    step('estimating the delay')
    rest_command = segmentation.rest
    pieces = split_long(segmentation.experiments, PIECE_SAMPLES, max_delay_samples)
    delay = estimate_delay(thin(pieces, DELAY_SAMPLES), dt, max_delay=max_delay_samples,
                           rest=rest_command, noise=segmentation.noise_std)
    sample = thin(pieces, SEARCH_SAMPLES)
    trial = thin_evenly(sample, COMPARE_SAMPLES, rest_command)
    limits = angle_limits
    low_stop, high_stop = segmentation.end_stops
    if limits is None and low_stop is not None and high_stop is not None:
        limits = (low_stop, high_stop)
    checks: list[HeldOut] = []
    if delay.lag > 0.0:
        lag_check = check_lag(trial, delay, dt, rest_command, max_delay_samples)
        checks.append(lag_check)
        if not lag_check.kept:
            delay = delay.without_lag(dt)
    points = tuple(level_speeds(pieces, delay.samples, dt, rest=rest_command))
    data = FitData(pieces, delay.samples, dt, delay.lag)
    search = data if len(sample) == len(pieces) else FitData(sample, delay.samples, dt,
                                                             delay.lag)
    step('fitting the static map')
    sdp_fit = fit_sdp(search, points, rest_command, method=method,
                      polish=None if search is data else data)
    comparison: tuple[KindScore, ...] = ()
    chosen: FittedKind = 'sdp' if kind == 'auto' else kind
    if kind == 'auto':
        step('comparing map families on held-out experiments')
        comparison = tuple(compare_kinds(trial, delay.samples, dt, rest_command, method,
                                         FIRST_KINDS, lag=delay.lag))
        chosen = choose_kind(comparison)
        if chosen != 'sdp':
            # Eq. (5) lost: try its generalisation, convex from the dead-zone.
            comparison += tuple(compare_kinds(trial, delay.samples, dt, rest_command, method,
                                              ('power_sat',), lag=delay.lag))
            chosen = choose_kind(comparison)
    fit: MapFit[StaticMap] = sdp_fit if chosen == 'sdp' else _fit_kind(
        chosen, data, points, rest_command, method, sdp_fit.static_map)
    effects: tuple[Effect, ...] = (ValveLag(delay.lag),) if delay.lag > 0.0 else ()
    model = JointModel(joint=next(iter(joints)) or 'joint', static_map=fit.static_map,
                       delay=whole_samples_seconds(delay.samples, dt), angle_limits=limits,
                       input_limits=input_limits, effects=effects)
    mae = data.simulation_mae(fit.static_map.rate)
    stops = limits if limits is not None else (low_stop, high_stop)
    reach = stop_reach(segmentation.noise_std)
    geometry = fit_stroke_geometry(sample, fit.static_map.rate, delay.samples, dt, delay.lag,
                                   stops, reach)
    if geometry is not None:
        geometry_check = check_geometry(trial, model, delay, dt, stops, reach)
        checks.append(geometry_check)
        if geometry_check.kept:
            shaped, refit = shape_with_geometry(
                model, geometry, lambda gained: _fit_kind(chosen, gained, points, rest_command,
                                                          method, sdp_fit.static_map),
                fit, pieces, sample, delay, dt, stops, reach)
            if shaped is not None:
                model, fit, mae = shaped, refit, experiments_mae(shaped, pieces, dt)
    return Identification(model, dt, delay, segmentation, points, fit, comparison, mae,
                          tuple(checks))

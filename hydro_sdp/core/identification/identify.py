"""
Offline identification of a hydraulic joint from records (the ``identify`` command).

The reasoning is in docs/methods.md sections 2, 13.

"""

from __future__ import annotations

from dataclasses import dataclass, replace
import math
from typing import Callable, Sequence

from hydro_sdp.core.errors import DataError
from hydro_sdp.core.identification.change_windows import ChangeWindows
from hydro_sdp.core.identification.delay import (
    DelayEstimate, estimate_delay, level_speeds, LevelSpeed)
from hydro_sdp.core.identification.determined import (
    moving_levels_a_side, parameters, undetermined_edges, unpinned)
from hydro_sdp.core.identification.effect_check import HeldOut, simulation_errors
from hydro_sdp.core.identification.end_stops import stop_reach
from hydro_sdp.core.identification.experiment import (
    Experiment, split_long, thin, thin_evenly)
from hydro_sdp.core.identification.family_choice import (
    compare_kinds, FIRST_KINDS, fit_family, FittedKind, FoldErrors, FoldFits, KindChoice, KINDS,
    KindScore)
from hydro_sdp.core.identification.identified import Identification, IdentifyStage
from hydro_sdp.core.identification.limits import model_limits
from hydro_sdp.core.identification.map_fit import FIT_METHODS, fit_sdp, FitData, FitMethod, MapFit
from hydro_sdp.core.identification.own_effects import (
    check_geometry, check_lag, shape_with_geometry)
from hydro_sdp.core.identification.routine.detect import routine_operation
from hydro_sdp.core.identification.routine.pipeline import identify_routine
from hydro_sdp.core.identification.segmentation import (
    check_records, segment_records, Segmentation)
from hydro_sdp.core.identification.stroke_fit import fit_stroke_geometry
from hydro_sdp.core.model.effects import Effect, ValveLag
from hydro_sdp.core.model.joint_model import JointModel
from hydro_sdp.core.model.records import Record
from hydro_sdp.core.model.sample_period import whole_samples_seconds
from hydro_sdp.core.model.static_maps import SdpMap, StaticMap
from hydro_sdp.core.model.timing import SamplePeriod

__all__ = ['experiments_mae', 'Identification', 'identify', 'IdentifyStage', 'KindChoice',
           'KINDS', 'KindScore', 'PIECE_SAMPLES']

#: Longest piece a fit sees, and the sample budgets of the multi-start search and the
#: delay search: long records are cut and thinned there, and the best start is then
#: refined on all the data.
PIECE_SAMPLES = 3000
SEARCH_SAMPLES = 60_000
DELAY_SAMPLES = 100_000
#: Sample budget of the held-out comparisons (map families, effects): every fold refits,
#: and a few hundred experiments score them as well as a thousand.
COMPARE_SAMPLES = 30_000


def experiments_mae(model: JointModel, experiments: Sequence[Experiment],
                    dt: SamplePeriod) -> float:
    """Mean absolute simulation error of a model over experiments, degrees (per sample)."""
    total, count = simulation_errors(model, experiments, dt)
    return total / max(count, 1)


@dataclass(frozen=True, eq=False)
class _Pieces:
    """The experiments a fit sees: all of them cut to length, and samples of them."""

    every: list[Experiment]
    search: list[Experiment]
    trial: list[Experiment]


def _segment(records: Sequence[Record], dt: SamplePeriod, max_delay: int,
             angle_limits: tuple[float, float] | None, rest: float | None,
             input_limits: tuple[float, float] | None) -> tuple[Segmentation, _Pieces]:
    """Cut the records into experiments, and those into the pieces and samples fits see."""
    segmentation = segment_records(records, max_delay=max_delay, angle_limits=angle_limits,
                                   rest=rest, input_limits=input_limits)
    if not segmentation.experiments:
        reasons = '; '.join(sorted({d.reason for d in segmentation.dropped})) or 'none found'
        raise DataError(f'no usable experiments ({reasons})')
    pieces = split_long(segmentation.experiments, PIECE_SAMPLES, max_delay)
    search = thin(pieces, SEARCH_SAMPLES)
    return segmentation, _Pieces(pieces, search,
                                 thin_evenly(search, COMPARE_SAMPLES, segmentation.rest))


def _delay(segmentation: Segmentation, pieces: _Pieces, dt: SamplePeriod, max_delay: int
           ) -> tuple[DelayEstimate, list[HeldOut]]:
    """Estimate the dead time with the valve lag, keeping the lag only if held-out data need it."""
    sample = thin(pieces.every, DELAY_SAMPLES)
    # The lag check's folds score the same windows with the same pairs as the fit.
    windows = ChangeWindows(sample, max_delay)
    delay = estimate_delay(sample, dt, max_delay=max_delay, rest=segmentation.rest,
                           noise=segmentation.noise_std, windows=windows)
    if delay.lag <= 0.0:
        return delay, []
    lag_check = check_lag(pieces.trial, delay, dt, segmentation.rest, max_delay, windows)
    return (delay if lag_check.kept else delay.without_lag(dt)), [lag_check]


@dataclass(frozen=True, eq=False)
class _MapStage:
    """The map fitted at one timing: the level speeds, the data, eq. (5) and the family."""

    points: tuple[LevelSpeed, ...]
    data: FitData
    sdp_fit: MapFit[SdpMap]
    fit: MapFit[StaticMap]


def _fit_sdp(pieces: _Pieces, delay: DelayEstimate, dt: SamplePeriod, rest: float,
             method: FitMethod, answer: bool) -> _MapStage:
    """Fit eq. (5) at this timing: the answer, or where another family starts."""
    points = tuple(level_speeds(pieces.every, delay.samples, dt, rest=rest))
    data = FitData(pieces.every, delay.samples, dt, delay.lag)
    search = data if len(pieces.search) == len(pieces.every) else FitData(
        pieces.search, delay.samples, dt, delay.lag)
    # Eq. (5) by the method asked when it may be the answer; for another family asked
    # for by name it is only a start (its dead-zone, its curvature): one regret fit.
    sdp_fit = fit_sdp(search, points, rest, method=method if answer else 'rr',
                      starts=4 if answer else 1, polish=None if search is data else data)
    return _MapStage(points, data, sdp_fit, sdp_fit)


def _fit_family(stage: _MapStage, kind: FittedKind, rest: float,
                method: FitMethod) -> _MapStage:
    """Fit the family chosen, from eq. (5)'s fit at the same timing."""
    if kind == 'sdp':
        return stage
    return replace(stage, fit=fit_family(kind, stage.data, stage.points, rest, method,
                                         stage.sdp_fit.static_map))


def _family(kind: KindChoice, pieces: _Pieces, delay: DelayEstimate, dt: SamplePeriod, rest: float,
            method: FitMethod, step: Callable[[IdentifyStage], None]
            ) -> tuple[FittedKind, FoldErrors | None]:
    """Return the map family asked for, or the one the held-out rule chooses."""
    if kind != 'auto':
        return kind, None
    step(IdentifyStage.FAMILIES)
    fold_fits = FoldFits(pieces.trial, delay.samples, dt, rest, method, delay.lag)
    comparison = compare_kinds(pieces.trial, delay.samples, dt, rest, method, FIRST_KINDS,
                               lag=delay.lag, fold_fits=fold_fits)
    if comparison.chosen() != 'sdp':
        # Eq. (5) lost: try its generalisation, convex from the dead-zone, on the same folds.
        comparison = comparison.merged(compare_kinds(
            pieces.trial, delay.samples, dt, rest, method, ('power_sat',), lag=delay.lag,
            fold_fits=fold_fits))
    return comparison.chosen(), comparison


def identify(records: Sequence[Record], *, method: FitMethod = 'rr', kind: KindChoice = 'auto',
             max_delay: float = 0.5, angle_limits: tuple[float, float] | None = None,
             input_limits: tuple[float, float] | None = None, rest: float | None = None,
             progress: Callable[[IdentifyStage], None] | None = None) -> Identification:
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
        Called with each :class:`IdentifyStage` as it starts.

    Returns
    -------
    Identification
        The model and the evidence.

    See Also
    --------
    Record : a record from arrays.
    evaluate, diagnose, design_from_model : what follows identification.

    Examples
    --------
    >>> import numpy as np
    >>> from hydro_sdp import identify, load_model, Record, simulate
    >>> truth = load_model('config/brokk_j2.yaml')
    >>> t = np.arange(0.0, 8.0, 0.01)
    >>> steps = [np.where(t < 1.0, 0.0, level) for level in (-6, -4, -2.5, 2.5, 4, 6)]
    >>> found = identify([Record(t, v, simulate(truth, v, 0.01, 30.0), joint='j2') for v in steps])
    >>> found.model.delay, found.model.static_map.kind
    (0.15, 'sdp')

    """
    if kind not in KINDS + ('auto',):
        raise DataError(f"kind must be auto, {', '.join(KINDS)}; got {kind!r}")
    if method not in FIT_METHODS:
        raise DataError(f"method must be 'rr' or 'oe', got {method!r}")
    dt = check_records(records)
    step = progress if progress is not None else (lambda stage: None)
    step(IdentifyStage.SEGMENTING)
    max_delay_samples = max(2, int(round(max_delay / dt)))
    segmentation, pieces = _segment(records, dt, max_delay_samples, angle_limits, rest,
                                    input_limits)
    rest_command = segmentation.rest
    # A closed loop or an operator holds few levels: the map from the increments.
    if routine_operation(records, rest_command, max_delay_samples):
        return identify_routine(records, segmentation, dt, max_delay=max_delay_samples,
                                kind=kind, angle_limits=angle_limits,
                                input_limits=input_limits, progress=step)
    step(IdentifyStage.DELAY)
    delay, checks = _delay(segmentation, pieces, dt, max_delay_samples)
    step(IdentifyStage.MAP)
    # Eq. (5) first: it refuses data that never moved the joint one way, naming why.
    stage = _fit_sdp(pieces, delay, dt, rest_command, method, kind in ('auto', 'sdp'))
    chosen, comparison = _family(kind, pieces, delay, dt, rest_command, method, step)
    stage = _fit_family(stage, chosen, rest_command, method)
    points, data, sdp_fit, fit = stage.points, stage.data, stage.sdp_fit, stage.fit
    low_stop, high_stop = segmentation.end_stops
    bounds = model_limits(records, segmentation.end_stops, rest_command,
                          angle_limits=angle_limits, input_limits=input_limits)
    limits = bounds.angle_limits
    effects: tuple[Effect, ...] = (ValveLag(delay.lag),) if delay.lag > 0.0 else ()
    model = JointModel(joint=records[0].joint or 'joint', static_map=fit.static_map,
                       delay=whole_samples_seconds(delay.samples, dt), angle_limits=limits,
                       input_limits=bounds.input_limits, effects=effects)
    mae = data.simulation_mae(fit.static_map.rate)
    # The speed along the stroke, kept only when held-out experiments need it.
    stops = limits if limits is not None else (low_stop, high_stop)
    reach = stop_reach(segmentation.noise_std)
    geometry = fit_stroke_geometry(pieces.search, fit.static_map.rate, delay.samples, dt,
                                   delay.lag, stops, reach)
    if geometry is not None:
        geometry_check = check_geometry(pieces.trial, model, delay, dt, stops, reach)
        checks.append(geometry_check)
        if geometry_check.kept:
            shaped, refit = shape_with_geometry(
                model, geometry, lambda gained: fit_family(chosen, gained, points, rest_command,
                                                           method, sdp_fit.static_map),
                fit, pieces.every, pieces.search, delay, dt, stops, reach)
            if shaped is not None:
                model, fit, mae = shaped, refit, experiments_mae(shaped, pieces.every, dt)
    # Which edges the data bound, from speeds past the valve's transient.
    settled = level_speeds(pieces.every, delay.samples, dt, rest=rest_command,
                           skip=int(math.ceil(delay.transient / dt)))
    model = replace(model, undetermined=undetermined_edges(settled, rest_command) + unpinned(
        dict(parameters(model)), fit.standard_errors, moving_levels_a_side(settled, rest_command)))
    scores = () if comparison is None else tuple(comparison.scores())
    return Identification(model, dt, delay, segmentation, points, fit, scores, mae,
                          tuple(checks), commands=bounds.commands,
                          family=None if comparison is None else comparison.judgement(),
                          fit_data=data, sdp_map=sdp_fit.static_map, method=method)

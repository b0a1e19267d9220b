"""
Identifying a joint from routine operation: the route ``identify`` takes for such records.

The reasoning is in docs/methods.md section 15.

"""

from __future__ import annotations

from typing import Callable, Sequence

from hydro_sdp.core.identification.determined import undetermined_edges
from hydro_sdp.core.identification.experiment import thin
from hydro_sdp.core.identification.family_choice import (
    FIRST_KINDS, FittedKind, FoldErrors, KindChoice)
from hydro_sdp.core.identification.identified import Identification, IdentifyStage
from hydro_sdp.core.identification.limits import model_limits
from hydro_sdp.core.identification.map_fit import FitData, MapFit
from hydro_sdp.core.identification.routine.family import compare_routine_kinds, routine_pieces
from hydro_sdp.core.identification.routine.increment_fit import (
    fit_increments, fit_sdp_increments)
from hydro_sdp.core.identification.routine.increments import increment_delay, increments_of
from hydro_sdp.core.identification.routine.speed_curve import check_coverage, speed_points
from hydro_sdp.core.identification.segmentation import Segmentation
from hydro_sdp.core.model.joint_model import JointModel
from hydro_sdp.core.model.records import Record
from hydro_sdp.core.model.sample_period import whole_samples_seconds
from hydro_sdp.core.model.static_maps import StaticMap
from hydro_sdp.core.model.timing import SamplePeriod

#: Sample budgets of the delay search and of the held-out comparison.
DELAY_SAMPLES = 100_000
COMPARE_SAMPLES = 60_000


def identify_routine(records: Sequence[Record], segmentation: Segmentation, dt: SamplePeriod, *,
                     max_delay: int, kind: KindChoice = 'auto',
                     angle_limits: tuple[float, float] | None = None,
                     input_limits: tuple[float, float] | None = None,
                     progress: Callable[[IdentifyStage], None] | None = None
                     ) -> Identification:
    """
    Identify a joint model from records of routine operation.

    ``dt``: sample period, s.
    ``max_delay``: largest delay considered, samples.
    ``angle_limits``, ``input_limits``: end stops and valve range given.
    ``progress``: called with each :class:`IdentifyStage` as it starts.
    """
    step = progress if progress is not None else (lambda stage: None)
    rest = segmentation.rest
    experiments = list(segmentation.experiments)
    pieces = routine_pieces(experiments, dt, max_delay)
    step(IdentifyStage.DELAY)
    delay = increment_delay(thin(pieces, DELAY_SAMPLES), dt, max_delay=max_delay, rest=rest)
    step(IdentifyStage.MAP)
    data = increments_of(experiments, delay.samples)
    points = speed_points(data, dt, rest)
    limits = model_limits(records, segmentation.end_stops, rest, angle_limits=angle_limits,
                          input_limits=input_limits)
    check_coverage(points, limits.commands.seen, rest, input_limits)
    sdp_fit = fit_sdp_increments(data, dt, points, rest)
    scores: FoldErrors | None = None
    chosen: FittedKind = 'sdp' if kind == 'auto' else kind
    if kind == 'auto':
        step(IdentifyStage.FAMILIES)
        trial = thin(pieces, COMPARE_SAMPLES)
        scores = compare_routine_kinds(trial, delay.samples, dt, rest, points, FIRST_KINDS)
        chosen = scores.chosen()
        if chosen != 'sdp':
            # Eq. (5) lost: try its generalisation, convex from the dead-zone.
            scores = scores.merged(compare_routine_kinds(trial, delay.samples, dt, rest,
                                                         points, ('power_sat',)))
            chosen = scores.chosen()
    fit: MapFit[StaticMap] = sdp_fit if chosen == 'sdp' else fit_increments(
        chosen, data, dt, points, rest, sdp_fit.static_map)
    model = JointModel(joint=records[0].joint or 'joint', static_map=fit.static_map,
                       delay=whole_samples_seconds(delay.samples, dt),
                       angle_limits=limits.angle_limits, input_limits=limits.input_limits,
                       undetermined=undetermined_edges(points, rest))
    mae = FitData(pieces, delay.samples, dt).simulation_mae(fit.static_map.rate)
    return Identification(model, dt, delay, segmentation, points, fit,
                          () if scores is None else tuple(scores.scores()), mae,
                          route='routine', commands=limits.commands,
                          family=None if scores is None else scores.judgement())

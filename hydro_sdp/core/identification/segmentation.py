"""Segmentation: records cut into the experiments that identification fits (methods 2.3, 2.6)."""

from __future__ import annotations

from dataclasses import dataclass, replace
import math
from typing import Sequence

from hydro_sdp.core.arrays import FloatArray
from hydro_sdp.core.errors import DataError
from hydro_sdp.core.identification.end_stops import (
    arrival_at_stop, clamp_start, pushes_into_stop, stop_reach, stop_tolerance, stop_window)
from hydro_sdp.core.identification.experiment import Experiment, MIN_SAMPLES
from hydro_sdp.core.identification.rest import estimate_rest_command
from hydro_sdp.core.model.records import Record
from hydro_sdp.core.model.sample_period import nominal_period
from hydro_sdp.core.model.timing import SamplePeriod
import numpy as np


@dataclass(frozen=True)
class Dropped:
    """
    A segment that was not used, and why.

    Attributes
    ----------
    t0 : float
        Record time where it started, s.
    since_start : float
        The same time counted from the start of the record's bag, s (for messages).
    angle : float
        Where the joint was held, degrees (NaN unless it was).

    """

    t0: float
    reason: str
    source: str = ''
    since_start: float = math.nan
    angle: float = math.nan

    @property
    def stalled(self) -> bool:
        """Whether the segment stalled: driven, not moving, not at a stop."""
        return self.reason.startswith(STALLED)


#: How a stalled segment's reason starts.
STALLED = 'stalled'


@dataclass(frozen=True, eq=False)
class Segmentation:
    """
    Experiments cut from records, with what was dropped and the noise level.

    Attributes
    ----------
    noise_std : float
        Angle measurement noise estimated at rest, degrees.
    end_stops : tuple[float | None, float | None]
        Angles where the joint was seen clamped (lower, upper), degrees.

    """

    experiments: tuple[Experiment, ...]
    dropped: tuple[Dropped, ...]
    rest: float
    noise_std: float
    end_stops: tuple[float | None, float | None]

    @property
    def steps(self) -> int:
        """Return the number of step experiments."""
        return sum(e.kind == 'step' for e in self.experiments)

    @property
    def runs(self) -> int:
        """Return the number of run experiments."""
        return sum(e.kind == 'run' for e in self.experiments)


def check_record(record: Record, *, min_samples: int = 50,
                 max_gap: float = 3.0) -> SamplePeriod:
    """
    Check that a record can be identified from, and return its sample period.

    ``min_samples``: fewest samples accepted.
    ``max_gap``: largest accepted spacing of time stamps, in sample periods.
    Returns: nominal sample period, s (:func:`hydro_sdp.core.model.sample_period.nominal_period`).
    Raises DataError naming the problem: too few samples, or a gap in the time stamps (records are
    cut at gaps by :func:`hydro_sdp.core.model.records.split_at_gaps` when they are read from
    bags).
    """
    label = record.source or 'record'
    if len(record) < min_samples:
        raise DataError(f'{label}: too few samples ({len(record)}; need at least {min_samples})')
    steps = np.diff(record.t)
    period = record.sample_period
    gaps = np.flatnonzero(steps > max_gap * period)
    if gaps.size:
        k = int(gaps[0])
        raise DataError(f'{label}: gap of {steps[k]:.3f} s in the time stamps '
                        f'{record.since_start(record.t[k]):.3f} s from the start (sample period '
                        f'{period:.4f} s); cut the record there (split_at_gaps)')
    return period


def check_records(records: Sequence[Record], task: str = 'identify') -> SamplePeriod:
    """
    Check records of one joint for a fit, and return their common nominal sample period.

    Returns: the nominal period of all their spacings together, s, so that records of one timer
    give one period whatever their length.
    Raises DataError without records, with records of several joints, or with periods more than 1 %
    apart (each record is checked by :func:`check_record`).
    """
    if not records:
        raise DataError(f'no records to {task} from')
    joints = {record.joint for record in records}
    if len(joints) > 1:
        raise DataError(f"records of several joints ({', '.join(sorted(joints))}); "
                        f'{task} one joint at a time')
    periods = [check_record(record) for record in records]
    if max(periods) > 1.01 * min(periods):
        raise DataError(f'records have different sample periods ({min(periods):.4g} s to '
                        f'{max(periods):.4g} s); resample them first')
    steps = np.concatenate([np.diff(record.t) for record in records])
    return SamplePeriod(nominal_period(steps))


def noise_level(record: Record, rest: float, settle: int) -> float:
    """
    Estimate the angle noise from samples taken well after the command went to rest.

    ``settle``: samples after the command reaches rest before the joint is taken as still.
    Returns: standard deviation of the angle noise, degrees (robust, from differences).
    """
    at_rest = record.v == rest
    # A sample counts when the command has rested for `settle` samples before it.
    run = np.convolve(at_rest.astype(np.int64), np.ones(settle + 1, dtype=np.int64))[
        :at_rest.size] == settle + 1
    differences = np.diff(record.y)[run[1:]]
    if differences.size < 10:
        differences = np.diff(np.diff(record.y)) / math.sqrt(3.0)
    deviation = np.median(np.abs(differences - np.median(differences)))
    return float(1.4826 * deviation / math.sqrt(2.0))


def _blocks(v: FloatArray, rest: float) -> list[tuple[int, int]]:
    active = v != rest
    edges = np.flatnonzero(np.diff(np.r_[0, active.astype(np.int8), 0]))
    return list(zip(edges[::2].tolist(), edges[1::2].tolist()))


def segment_record(record: Record, *, max_delay: int, rest: float | None = None,
                   angle_limits: tuple[float, float] | None = None,
                   min_samples: int = MIN_SAMPLES) -> Segmentation:
    """
    Cut a record into step and run experiments.

    ``max_delay``: largest delay considered, samples: the history kept before each experiment and
    the tail kept after its command returns to rest.
    ``rest``: rest command; default:
    :func:`~hydro_sdp.core.identification.rest.estimate_rest_command`.
    ``angle_limits``: known end stops; default: detected where the joint is held still while
    driven.
    ``min_samples``: fewest predicted samples an experiment needs.
    """
    v, y = record.v, record.y
    rest = estimate_rest_command([(v, y)]) if rest is None else rest
    noise = noise_level(record, rest, max_delay)
    blocks = _blocks(v, rest)
    window = (stop_window(SamplePeriod(float(np.median(np.diff(record.t)))))
              if len(record) > 1 else 5)
    extremes = (float(np.min(y)), float(np.max(y))) if len(record) else (0.0, 0.0)
    experiments: list[Experiment] = []
    dropped: list[Dropped] = []
    stops: list[list[float]] = [[], []]
    for index, (begin, end) in enumerate(blocks):
        start = max(begin - 1, 0)
        next_begin = blocks[index + 1][0] if index + 1 < len(blocks) else v.size
        block_stop = min(end + max_delay, next_begin, v.size)
        held = np.all(v[begin:end] == v[begin])
        if block_stop - start - 1 < min_samples:
            dropped.append(Dropped(float(record.t[start]),
                                   f'too short ({max(block_stop - start - 1, 0)} samples)',
                                   record.source, record.since_start(record.t[start])))
            continue
        # A block may meet the end stops several times: cut out each stretch the joint
        # is held, and go on where it leaves the stop.
        while block_stop - start - 1 >= min_samples:
            clamp = clamp_start(y, v, start, block_stop, delay=max_delay, noise=noise,
                                window=window, limits=angle_limits, extremes=extremes,
                                rest=rest)
            stop = block_stop if clamp is None else clamp[0]
            if stop - start - 1 >= min_samples:
                history = max(start - max_delay, 0)
                experiments.append(Experiment(
                    v=v[history:stop], y=y[history:stop], start=start - history,
                    kind='step' if held else 'run',
                    level=float(v[begin]) if held else math.nan, t0=float(record.t[start]),
                    source=record.source))
            if clamp is None:
                break
            # The joint leaves the stop only once the command that holds it there has
            # changed and the change has come through the delay.
            changed = np.flatnonzero(v[stop:block_stop] != v[stop])
            released = min(stop + int(changed[0]) + max_delay, block_stop) \
                if changed.size else block_stop
            stops[clamp[2]].append(clamp[1])
            dropped.append(Dropped(float(record.t[stop]), 'clamped by an end stop',
                                   record.source, record.since_start(record.t[stop]),
                                   clamp[1]))
            start = released
    # A joint cannot be held beyond its stop: the outermost angle held is the stop.
    end_stops = (float(np.min(stops[0])) if stops[0] else None,
                 float(np.max(stops[1])) if stops[1] else None)
    if angle_limits is not None:
        end_stops = angle_limits
    kept, at_stop = _drop_held(experiments, end_stops, rest, record, noise)
    return Segmentation(kept, tuple(dropped) + at_stop, rest, noise, end_stops)


def _drop_held(experiments: Sequence[Experiment], stops: tuple[float | None, float | None],
               rest: float, record: Record, noise: float) -> tuple[tuple[Experiment, ...],
                                                                   tuple[Dropped, ...]]:
    # Steps that start at a stop and push into it: zero speed there is true but
    # says nothing about the valve.
    held = [e for e in experiments if e.kind == 'step'
            and pushes_into_stop(e.y[e.start:], e.level, rest, stops)]
    kept, dropped = [], []
    for e in experiments:
        if e in held:
            dropped.append(Dropped(e.t0, 'held against an end stop', record.source,
                                   record.since_start(e.t0)))
            continue
        trimmed = _trim_at_stop(e, stops, rest, stop_reach(noise))
        if trimmed is None:
            dropped.append(Dropped(e.t0, 'clamped by an end stop', record.source,
                                   record.since_start(e.t0)))
        else:
            kept.append(trimmed)
    return tuple(kept), tuple(dropped)


def _trim_at_stop(experiment: Experiment, stops: tuple[float | None, float | None],
                  rest: float, reach: float) -> Experiment | None:
    """Cut a step where it arrives at the stop its command drives into (None: too short)."""
    if experiment.kind != 'step':
        return experiment
    arrival = arrival_at_stop(experiment.y[experiment.start:], experiment.level, rest, stops,
                              reach)
    if arrival is None:
        return experiment
    if arrival < MIN_SAMPLES:
        return None
    stop = experiment.start + arrival + 1
    return Experiment(experiment.v[:stop], experiment.y[:stop], experiment.start,
                      experiment.kind, experiment.level, experiment.t0, experiment.source)


def segment_records(records: Sequence[Record], *, max_delay: int,
                    angle_limits: tuple[float, float] | None = None,
                    rest: float | None = None,
                    input_limits: tuple[float, float] | None = None) -> Segmentation:
    """
    Segment several records of one joint and pool the experiments.

    The records are put in a canonical order first (by source, start time and
    content), so the order they are given in changes nothing.

    ``records``: records of the same joint at the same sample period.
    ``max_delay``: largest delay considered, samples.
    ``angle_limits``: known end stops.
    ``rest``: rest (neutral) command; default: from the data
    (:func:`~hydro_sdp.core.identification.rest.estimate_rest_command`).
    ``input_limits``: command range of the valve (its middle is the preferred rest when it excludes
    0).
    """
    if not records:
        raise DataError('no records to identify from')
    ordered = sorted(records, key=_record_key)
    if rest is None:
        rest = estimate_rest_command([(r.v, r.y) for r in ordered], input_limits=input_limits)
    parts = [segment_record(r, max_delay=max_delay, rest=rest, angle_limits=angle_limits)
             for r in ordered]
    lows = [p.end_stops[0] for p in parts if p.end_stops[0] is not None]
    highs = [p.end_stops[1] for p in parts if p.end_stops[1] is not None]
    stops = (min(lows) if lows else None, max(highs) if highs else None)
    if angle_limits is None:
        stops = _never_passed(stops, ordered)
    # A stop seen in one record holds in the others.
    held = [_drop_held(p.experiments, stops, rest, r, p.noise_std)
            for p, r in zip(parts, ordered)]
    noise = float(np.median([p.noise_std for p in parts]))
    experiments, stalled = _drop_stalled([e for kept, _ in held for e in kept], rest, noise)
    dropped = [_stall_or_stop(d, stops) for p, (_, more) in zip(parts, held)
               for d in p.dropped + more]
    return Segmentation(tuple(experiments), tuple(dropped) + stalled, rest, noise, stops)


def _never_passed(stops: tuple[float | None, float | None],
                  records: Sequence[Record]) -> tuple[float | None, float | None]:
    # A stop is the far end of the travel: an angle some record passes is a stall.
    tolerance = stop_tolerance(stops)
    low = min(float(np.min(r.y)) for r in records)
    high = max(float(np.max(r.y)) for r in records)
    return (stops[0] if stops[0] is not None and stops[0] - low <= tolerance else None,
            stops[1] if stops[1] is not None and high - stops[1] <= tolerance else None)


def _stall_or_stop(dropped: Dropped, stops: tuple[float | None, float | None]) -> Dropped:
    """Relabel a segment held short of the stop on its side as stalled."""
    if not math.isfinite(dropped.angle):
        return dropped
    tolerance = stop_tolerance(stops)
    low, high = stops
    if (low is not None and abs(dropped.angle - low) <= tolerance) or \
            (high is not None and abs(dropped.angle - high) <= tolerance):
        return dropped
    return replace(dropped, reason=f'{STALLED}: held at {dropped.angle:.4g} deg while driven, '
                                   'short of any end stop')


def _drop_stalled(experiments: Sequence[Experiment], rest: float, noise: float
                  ) -> tuple[list[Experiment], tuple[Dropped, ...]]:
    """Leave out steps that did not move where a command no larger moved the joint elsewhere."""
    steps = [e for e in experiments if e.kind == 'step' and e.level != rest and e.samples > 0]
    net = {id(e): float(e.y[-1] - e.y[e.start]) / e.samples for e in steps}
    fastest = max((abs(speed) for speed in net.values()), default=0.0)

    def moves(e: Experiment) -> bool:
        speed = net[id(e)]
        return bool(np.sign(speed) == np.sign(e.level - rest)
                    and abs(speed) > max(10.0 * noise / e.samples, 0.02 * fastest))
    moving = [e for e in steps if moves(e)]
    stalled = [e for e in steps if not moves(e) and any(
        np.sign(m.level - rest) == np.sign(e.level - rest)
        and abs(m.level - rest) <= abs(e.level - rest) for m in moving)]
    gone = {id(e) for e in stalled}
    return [e for e in experiments if id(e) not in gone], tuple(
        Dropped(e.t0, f'{STALLED}: commanded {e.level:.4g} and did not move, where a command '
                      'no larger moved the joint in another run', e.source)
        for e in stalled)


def _record_key(record: Record) -> tuple[str, float, int, float, float]:
    return (record.source, float(record.t[0]) if len(record) else 0.0, len(record),
            float(np.sum(record.v)), float(np.sum(record.y)))

"""
The samples of a joint's records as rows of the SDP analysis, and the candidate states.

The reasoning is in docs/methods.md section 14.6.

"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

from hydro_sdp.core.arrays import FloatArray, IntArray
from hydro_sdp.core.errors import ConfigurationError, DataError
from hydro_sdp.core.identification.effect_check import at_stop
from hydro_sdp.core.identification.end_stops import (
    clamp_start, HELD_FRACTION, stop_reach, stop_tolerance, stop_window)
from hydro_sdp.core.identification.segmentation import noise_level
from hydro_sdp.core.model.exogenous_signals import exogenous_of, smoothed_speeds
from hydro_sdp.core.model.joint_model import JointModel
from hydro_sdp.core.model.records import Record
from hydro_sdp.core.model.simulation import one_step_increments
from hydro_sdp.core.model.timing import SamplePeriod
import numpy as np

#: The candidate states, in the order they are analysed.
STATES: tuple[str, ...] = ('command', 'angle', 'since_change', 'others_speed', 'load',
                           'reversals')
#: Units of each state, for figures and reports.
UNITS = {'command': 'input units', 'angle': 'deg', 'since_change': 's',
         'others_speed': 'deg/s', 'load': 'load units', 'reversals': 'deg'}
#: Why a row is left out, by its :attr:`Rows.hold` code (0: kept).
HOLDS = {1: 'held at an end stop while the command drives into it',
         2: 'stalled: driven, not moving, away from the stops',
         3: 'resting at an end stop'}


@dataclass(frozen=True, eq=False)
class Rows:
    """
    One row per angle increment of all records.

    Attributes
    ----------
    y : FloatArray
        Angle ``y_k``, deg.
    previous : FloatArray
        Angle ``y_{k-1}``, deg.
    command : FloatArray
        Delayed command ``v_{k-tau}``, input units.
    drive : FloatArray
        ``v_{k-tau} - rest``: the command that drives the joint.
    since_change : FloatArray
        Time since the delayed command last changed, s.
    others_speed : FloatArray or None
        Other joints' summed absolute speed, deg/s (None: no other joints).
    load : FloatArray or None
        Measured load (None: no load signal).
    predicted : FloatArray or None
        The model's one-step increment, deg (None without a model).
    reversals : FloatArray or None
        Travel since the motion last reversed, deg.
    angle : FloatArray or None
        Angle ``y_{k-2}``, deg (None: ``previous``).
    hold : IntArray or None
        Why the joint cannot move at each row (:data:`HOLDS`; 0: it can); None: not looked for.
    run : IntArray or None
        Index of the run each row belongs to: a delayed command held, within one record (None: one
        run per row).

    """

    y: FloatArray
    previous: FloatArray
    command: FloatArray
    drive: FloatArray
    since_change: FloatArray
    others_speed: FloatArray | None
    load: FloatArray | None
    record: IntArray
    predicted: FloatArray | None = None
    reversals: FloatArray | None = None
    angle: FloatArray | None = None
    hold: IntArray | None = None
    run: IntArray | None = None

    @property
    def samples(self) -> int:
        """Return the number of rows."""
        return int(self.y.size)

    def every(self, stride: int) -> Rows:
        """Return every ``stride``-th row (each record's rows stay in time order)."""
        if stride <= 1:
            return self
        return self._pick(slice(None, None, stride))

    def free(self) -> tuple[Rows, dict[str, int]]:
        """Return the rows where the joint can move, and how many were left out, by reason."""
        if self.hold is None or not np.any(self.hold):
            return self, {}
        counts = np.bincount(self.hold, minlength=len(HOLDS) + 1)
        left = {HOLDS[code]: int(counts[code]) for code in HOLDS if counts[code]}
        return self._pick(self.hold == 0), left

    def _pick(self, pick: slice | IntArray) -> Rows:
        def kept(values: FloatArray | None) -> FloatArray | None:
            return None if values is None else values[pick]
        return Rows(self.y[pick], self.previous[pick], self.command[pick], self.drive[pick],
                    self.since_change[pick], kept(self.others_speed), kept(self.load),
                    self.record[pick], kept(self.predicted), kept(self.reversals),
                    kept(self.angle), None if self.hold is None else self.hold[pick],
                    None if self.run is None else self.run[pick])

    @property
    def increment(self) -> FloatArray:
        """Return the measured increments ``y_k - y_{k-1}``, deg."""
        return self.y - self.previous

    def state(self, name: str) -> FloatArray:
        """
        Return a candidate state at every row.

        ``name``: one of :data:`STATES`.
        Raises DataError when the records do not carry it (no other joints, no load).
        """
        if name == 'command':
            return self.command
        if name == 'angle':
            return self.previous if self.angle is None else self.angle
        if name == 'since_change':
            return self.since_change
        if name == 'others_speed':
            if self.others_speed is None:
                raise DataError('others_speed: the records carry no other joints')
            return self.others_speed
        if name == 'load':
            if self.load is None:
                raise DataError('load: the records carry no load signal (--load-topic)')
            return self.load
        if name == 'reversals':
            if self.reversals is None:
                raise DataError('reversals: not computed for these rows')
            return self.reversals
        raise ConfigurationError(f"unknown state {name!r}; choose from {', '.join(STATES)}")


def check_states(names: Sequence[str]) -> tuple[str, ...]:
    """Return the state names, refusing unknown or repeated ones."""
    unknown = [name for name in names if name not in STATES]
    if unknown:
        choices = ', '.join(STATES)
        raise ConfigurationError(f'unknown state {unknown[0]!r}; choose from {choices}')
    if not names:
        raise ConfigurationError('no states to analyse')
    if len(set(names)) != len(names):
        raise ConfigurationError(f"a state is named twice in {', '.join(names)}")
    return tuple(names)


def _since_change(t: FloatArray, delayed: FloatArray) -> FloatArray:
    """Time from the last change of ``delayed`` (or the first sample) to each sample, s."""
    changed = np.r_[True, delayed[1:] != delayed[:-1]]
    index = np.arange(delayed.size)
    last = np.maximum.accumulate(np.where(changed, index, 0))
    # A change between samples j-1 and j shows in the increment ending at t_j: count from t_{j-1}.
    origin = t[np.maximum(last - 1, 0)]
    return t - origin


def travel_since_reversal(direction: FloatArray, travel: FloatArray) -> FloatArray:
    """
    Return the travel since the direction last reversed, before each step.

    ``direction``: sign of the motion at each step (0: no direction, the last one holds).
    ``travel``: length of each step (>= 0).
    """
    direction = np.sign(np.asarray(direction, dtype=np.float64))
    index = np.arange(direction.size)
    last = np.maximum.accumulate(np.where(direction != 0.0, index, 0))
    held = direction[last]
    start = np.r_[True, held[1:] != held[:-1]]
    origin = np.maximum.accumulate(np.where(start, index, 0))
    before = np.r_[0.0, np.cumsum(np.asarray(travel, dtype=np.float64))[:-1]]
    return before - before[origin]


def rows_of(records: Sequence[Record], delay: int, rest: float,
            model: JointModel | None = None, dt: SamplePeriod | None = None, *,
            holds: bool = False) -> Rows:
    """
    Build the rows of the SDP analysis from records of one joint.

    ``records``: the records (same joint, same sample period).
    ``delay``: delay ``tau``, samples (>= 1).
    ``rest``: the valve's rest command.
    ``model``: a model whose one-step increments are added as ``predicted``.
    ``dt``: sample period, s (for the model); default: each record's own.
    ``holds``: whether to mark the rows where the joint is held (:func:`holds_of`).
    """
    if delay < 1:
        raise DataError(f'delay must be at least one sample, got {delay}')
    parts: dict[str, list[FloatArray]] = {key: [] for key in (
        'y', 'previous', 'angle', 'command', 'since', 'others', 'load', 'predicted',
        'reversals')}
    hold: list[IntArray] = []
    runs: list[IntArray] = []
    extremes = (min(float(np.min(r.y)) for r in records if len(r)),
                max(float(np.max(r.y)) for r in records if len(r))) if holds else (0.0, 0.0)
    owner: list[IntArray] = []
    have_others = all(r.others is not None and r.others.shape[1] > 0 for r in records)
    have_load = all(r.load is not None for r in records)
    for i, record in enumerate(records):
        n = len(record)
        if n <= delay + 1:
            continue
        k = np.arange(delay, n)
        delayed = record.v[k - delay]
        parts['y'].append(record.y[k])
        parts['previous'].append(record.y[k - 1])
        parts['angle'].append(record.y[np.maximum(k - 2, 0)])
        parts['command'].append(delayed)
        parts['since'].append(_since_change(record.t[k], delayed))
        period = dt or record.sample_period
        if have_others:
            assert record.others is not None
            speeds = smoothed_speeds(record.others, period, record.t)
            parts['others'].append(np.abs(speeds).sum(axis=1)[k])
        if have_load:
            assert record.load is not None
            parts['load'].append(record.load[k - 1])
        if model is not None:
            increments = one_step_increments(model, record.v, record.y, period, start=delay - 1,
                                             v_before=float(record.v[0]),
                                             exogenous=exogenous_of(record, period))
            parts['predicted'].append(increments)
            parts['reversals'].append(travel_since_reversal(increments, np.abs(increments)))
        else:
            parts['reversals'].append(travel_since_reversal(
                delayed - rest, np.abs(record.y[k] - record.y[k - 1])))
        owner.append(np.full(k.size, i))
        first = runs[-1][-1] + 1 if runs else 0
        runs.append(first + np.cumsum(np.r_[0, delayed[1:] != delayed[:-1]]))
        if holds:
            hold.append(holds_of(record, delay, rest, model, extremes)[k])
    if not owner:
        raise DataError(f'every record is shorter than the delay ({delay} samples) + 2')
    command = np.concatenate(parts['command'])
    return Rows(np.concatenate(parts['y']), np.concatenate(parts['previous']), command,
                command - rest, np.concatenate(parts['since']),
                np.concatenate(parts['others']) if have_others else None,
                np.concatenate(parts['load']) if have_load else None,
                np.concatenate(owner),
                np.concatenate(parts['predicted']) if model is not None else None,
                np.concatenate(parts['reversals']), np.concatenate(parts['angle']),
                np.concatenate(hold) if holds else None, np.concatenate(runs))


def holds_of(record: Record, delay: int, rest: float, model: JointModel | None,
             extremes: tuple[float, float]) -> IntArray:
    """
    Mark the increments of a record the joint cannot make although it is driven.

    ``model``: the model: its stops, and its map for the direction a command drives (else the sign
    of ``v - rest``).
    ``extremes``: lowest and highest angle of all the records: a joint held there is at a stop.
    Returns: code of the increment ending at each sample (0 at the first ``delay``).
    """
    v, y = record.v, record.y
    n = y.size
    code = np.zeros(n, dtype=np.int64)
    if n <= delay + 1:
        return code
    noise = noise_level(record, rest, delay)
    reach = stop_reach(noise)
    window = stop_window(record.sample_period)
    k = np.arange(delay, n)
    drive = (model.rate(v[k - delay]) if model is not None else v[k - delay] - rest)
    held = np.zeros(n, dtype=bool)
    held[k] = stalled(y, v, delay, noise, window)[k] & (drive != 0.0)
    # Both ends of an increment held: the first increment out of a stall is motion.
    code[1:] = np.where(held[1:] & held[:-1], 2, 0)
    known: tuple[float | None, float | None] = (
        model.angle_limits if model is not None and model.angle_limits is not None
        else _stops_found(record, delay, rest, noise, window, extremes))
    stops = (-np.inf if known[0] is None else known[0], np.inf if known[1] is None else known[1])
    previous = y[k - 1]
    # Held just short of a stop (the net speed's window reaches it) is arriving there.
    near = max(reach, stop_tolerance(known))
    code[k[(code[k] == 2) & at_stop(previous, drive, stops, near)]] = 1
    code[k[at_stop(previous, drive, stops, reach)]] = 1
    middle = 0.5 * (max(stops[0], extremes[0]) + min(stops[1], extremes[1]))
    still = np.where(drive == 0.0, np.where(previous > middle, 1.0, -1.0), 0.0)
    code[k[at_stop(previous, still, stops, reach)]] = 3
    return code


def stalled(y: FloatArray, v: FloatArray, delay: int, noise: float, window: int) -> np.ndarray:
    """
    Mark the samples where the joint is held after moving under the same delayed command.

    ``y``, ``v``: angles (deg) and commands of a record.
    ``noise``: angle noise, deg.
    Returns: whether each sample is held so (False at the last ``window`` and first ``delay``).
    """
    n = y.size
    held = np.zeros(n, dtype=bool)
    if n <= delay + window + 1:
        return held
    speed = np.zeros(n)
    speed[:n - window] = np.abs(y[window:] - y[:-window]) / window
    delayed = np.r_[np.full(delay, np.nan), v[:n - delay]]
    start = np.r_[True, ~(delayed[1:] == delayed[:-1])]
    index = np.arange(n)
    since = index - np.maximum.accumulate(np.where(start, index, 0))
    run = np.cumsum(start)
    # Samples to the end of the run: the window must not see the next command.
    ends = np.r_[np.flatnonzero(start)[1:], n]
    left = ends[run - 1] - index
    # The fastest so far within each run (from two windows in), by one running maximum:
    # each run lifted above every earlier one.
    counted = np.where(since >= 2 * window, speed, 0.0)
    lift = run * (float(np.max(speed)) + 1.0)
    fastest = np.maximum.accumulate(counted + lift) - lift
    floor = 4.0 * max(noise, 1e-9) / window
    held[:n - window] = ((speed < np.maximum(HELD_FRACTION * fastest, floor))
                         & (fastest > 3.0 * floor) & (since >= 2 * window)
                         & (left >= window))[:n - window]
    return held


def _stops_found(record: Record, delay: int, rest: float, noise: float, window: int,
                 extremes: tuple[float, float]) -> tuple[float | None, float | None]:
    """Return the angles the joint is held at, driven, at the ends of its travel."""
    v, y = record.v, record.y
    n = y.size
    found: list[list[float]] = [[], []]
    active = np.flatnonzero(np.diff(np.r_[0, (v != rest).astype(np.int8), 0]))
    for begin, end in zip(active[::2].tolist(), active[1::2].tolist()):
        start, stop = max(begin - 1, 0), min(end + delay, n)
        while stop - start > 2 * window + 2:
            clamp = clamp_start(y, v, start, stop, delay=delay, noise=noise, window=window,
                                extremes=extremes, rest=rest)
            if clamp is None:
                break
            arrival, angle, side = clamp
            found[side].append(angle)
            changed = np.flatnonzero(v[arrival:stop] != v[arrival])
            start = min(arrival + int(changed[0]) + delay, stop) if changed.size else stop
    return (min(found[0]) if found[0] else None, max(found[1]) if found[1] else None)

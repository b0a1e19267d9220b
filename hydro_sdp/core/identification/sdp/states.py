"""
The samples of a joint's records as rows of the SDP analysis, and the candidate states.

One row per angle increment ``y_k - y_{k-1}`` whose delayed command
``v_{k-tau}`` lies inside its record. The candidate states a parameter may
depend on, by name:

* ``command``: the delayed command ``v_{k-tau}`` (input units);
* ``angle``: the angle ``y_{k-1}`` the increment starts from (deg); the
  analysis splits every gain by the direction of motion, so each direction
  gets its own curve along the angle;
* ``since_change``: time from the last change of the delayed command to
  ``t_k`` (s; from the record's start before its first change);
* ``others_speed``: the other joints' absolute speeds summed (deg/s, the
  trailing mean of :func:`~hydro_sdp.core.model.exogenous_signals.smoothed_speeds`),
  from the JointState's other joints;
* ``load``: the measured load in force over the increment (its own units);
* ``reversals``: the travel since the motion last reversed (deg) before the
  increment: the model's travel since its motion reversed when a model is given
  (what backlash hides from the sensor after each reversal), else the measured
  travel since the drive last changed sign.

"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

from hydro_sdp.core.arrays import FloatArray, IntArray
from hydro_sdp.core.errors import ConfigurationError, DataError
from hydro_sdp.core.model.exogenous_signals import exogenous_of, smoothed_speeds
from hydro_sdp.core.model.joint_model import JointModel
from hydro_sdp.core.model.records import Record
from hydro_sdp.core.model.simulation import one_step_increments
import numpy as np

#: The candidate states, in the order they are analysed.
STATES: tuple[str, ...] = ('command', 'angle', 'since_change', 'others_speed', 'load',
                           'reversals')
#: Units of each state, for figures and reports.
UNITS = {'command': 'input units', 'angle': 'deg', 'since_change': 's',
         'others_speed': 'deg/s', 'load': 'load units', 'reversals': 'deg'}


@dataclass(frozen=True, eq=False)
class Rows:
    """
    One row per angle increment of all records.

    Parameters
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
    record : IntArray
        Index of the record each row comes from.
    predicted : FloatArray or None
        The model's one-step increment, deg (None without a model).
    reversals : FloatArray or None
        Travel since the motion last reversed, deg.

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

    @property
    def samples(self) -> int:
        """Return the number of rows."""
        return int(self.y.size)

    def every(self, stride: int) -> Rows:
        """Return every ``stride``-th row (each record's rows stay in time order)."""
        if stride <= 1:
            return self
        pick = slice(None, None, stride)

        def kept(values: FloatArray | None) -> FloatArray | None:
            return None if values is None else values[pick]
        return Rows(self.y[pick], self.previous[pick], self.command[pick], self.drive[pick],
                    self.since_change[pick], kept(self.others_speed), kept(self.load),
                    self.record[pick], kept(self.predicted), kept(self.reversals))

    @property
    def increment(self) -> FloatArray:
        """Return the measured increments ``y_k - y_{k-1}``, deg."""
        return self.y - self.previous

    def state(self, name: str) -> FloatArray:
        """
        Return a candidate state at every row.

        Parameters
        ----------
        name : str
            One of :data:`STATES`.

        Returns
        -------
        FloatArray
            The state.

        Raises
        ------
        DataError
            When the records do not carry it (no other joints, no load).

        """
        if name == 'command':
            return self.command
        if name == 'angle':
            return self.previous
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

    Parameters
    ----------
    direction : FloatArray
        Sign of the motion at each step (0: no direction, the last one holds).
    travel : FloatArray
        Length of each step (>= 0).

    Returns
    -------
    FloatArray
        The summed ``travel`` of the steps since the direction last changed, before
        each step (from the first step while it never changed).

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
            model: JointModel | None = None, dt: float | None = None) -> Rows:
    """
    Build the rows of the SDP analysis from records of one joint.

    Parameters
    ----------
    records : sequence of Record
        The records (same joint, same sample period).
    delay : int
        Delay ``tau``, samples (>= 1).
    rest : float
        The valve's rest command.
    model : JointModel or None
        A model whose one-step increments are added as ``predicted``.
    dt : float or None
        Sample period, s (for the model); default: each record's own.

    Returns
    -------
    Rows
        The rows of all records, record after record.

    """
    if delay < 1:
        raise DataError(f'delay must be at least one sample, got {delay}')
    parts: dict[str, list[FloatArray]] = {key: [] for key in (
        'y', 'previous', 'command', 'since', 'others', 'load', 'predicted', 'reversals')}
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
    if not owner:
        raise DataError(f'every record is shorter than the delay ({delay} samples) + 2')
    command = np.concatenate(parts['command'])
    return Rows(np.concatenate(parts['y']), np.concatenate(parts['previous']), command,
                command - rest, np.concatenate(parts['since']),
                np.concatenate(parts['others']) if have_others else None,
                np.concatenate(parts['load']) if have_load else None,
                np.concatenate(owner),
                np.concatenate(parts['predicted']) if model is not None else None,
                np.concatenate(parts['reversals']))

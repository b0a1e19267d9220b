"""Runs, simulation error and the velocity residual of the discrepancy workflow (methods 8.1)."""

from __future__ import annotations

from dataclasses import dataclass, replace
from functools import cached_property
from typing import Sequence

from hydro_sdp.core.arrays import FloatArray
from hydro_sdp.core.identification.end_stops import stop_window
from hydro_sdp.core.identification.evaluation import record_mae
from hydro_sdp.core.identification.segmentation import check_record
from hydro_sdp.core.identification.state_dependence.states import holds_of
from hydro_sdp.core.model.effects import AngleDependentVelocity, Backlash, Oscillation
from hydro_sdp.core.model.exogenous_signals import Exogenous, exogenous_of
from hydro_sdp.core.model.joint_model import JointModel
from hydro_sdp.core.model.records import Record
from hydro_sdp.core.model.simulation import bounded_cumsum, one_step_increments, speed_profile
from hydro_sdp.core.model.timing import SamplePeriod
import numpy as np

#: A candidate must remove at least this share of the squared velocity residual.
MIN_GAIN = 0.02
#: Length of the blocks residuals are summed over (and the shortest bootstrap block), s.
BLOCK_SECONDS = 1.0


@dataclass(frozen=True, eq=False)
class Run:
    """
    A record with the sample it is simulated from.

    Attributes
    ----------
    dt : float
        Its sample period, s.
    start : int
        First sample at which the joint's state is settled.
    free : numpy.ndarray or None
        Whether the joint can move over each increment from ``start`` (None: all).

    """

    record: Record
    dt: SamplePeriod
    start: int
    free: np.ndarray | None = None

    @cached_property
    def free_samples(self) -> np.ndarray | None:
        """Return whether each sample is free (None: all): ``free`` by the increment's end."""
        if self.free is None:
            return None
        return np.r_[np.ones(self.start + 1, dtype=bool), self.free]

    # Fits simulate a run hundreds of times; its signals do not change.
    @cached_property
    def exogenous(self) -> Exogenous:
        """Return the record's load and other joints' speeds, built once per run."""
        return exogenous_of(self.record, self.dt)


def _settled_start(record: Record, hold: int, fallback: int) -> int:
    """First sample after the command has stayed the same for ``hold`` samples."""
    changes = np.flatnonzero(np.diff(record.v)) + 1
    starts = np.r_[0, changes]
    ends = np.r_[changes, record.v.size]
    long = np.flatnonzero(ends - starts > hold)
    if long.size == 0:
        return fallback
    return min(int(starts[long[0]]) + hold, record.v.size - 2)


def runs_of(records: Sequence[Record], max_delay: float, settle: float = 1.0) -> list[Run]:
    """
    Wrap records with the sample each is simulated from.

    ``max_delay``: largest delay considered, s.
    ``settle``: shortest hold, s (0: every delayed command known is enough: the held-out runs a
    candidate is judged on, where a short run's first seconds count).
    Returns: one run per record.
    """
    runs = []
    for record in records:
        dt = check_record(record)
        hold = int(round(max(settle, max_delay) / dt))
        fallback = min(int(round(max_delay / dt)) + 1, len(record) - 2)
        runs.append(Run(record, dt, _settled_start(record, hold, fallback)))
    return runs


def mae(model: JointModel, runs: Sequence[Run]) -> float:
    """Return the mean absolute simulation error, averaged per record, degrees."""
    return float(np.mean([record_mae(model, run.record, run.dt, run.exogenous) for run in runs]))


def run_increments(model: JointModel, run: Run) -> FloatArray:
    """Return the one-step increments ``y^_k - y_{k-1}`` the model predicts over a run, deg."""
    record = run.record
    return one_step_increments(model, record.v, record.y, run.dt, start=run.start,
                               v_before=float(record.v[0]), exogenous=run.exogenous)


def velocity_residuals(model: JointModel, runs: Sequence[Run]) -> list[FloatArray]:
    """Return ``dy - dy^`` per run: measured increments against one-step predictions, deg."""
    out: list[FloatArray] = []
    for run in runs:
        predicted = _play_at_stops(model, run) if _plays_at_stops(model) else \
            run_increments(model, run)
        residual = np.diff(run.record.y[run.start:]) - predicted
        out.append(residual if run.free is None else np.where(run.free, residual, 0.0))
    return out


def free_runs(runs: Sequence[Run], model: JointModel, max_delay: int, rest: float
              ) -> list[Run]:
    """
    Mark the increments where the joint can move: not at a stop, not stalled.

    Held at a stop or stalled (``state_dependence.states.holds_of``,
    as the SDP analysis leaves them out), and for :func:`stop_window` after arriving at a
    stop under the same command, while the link rings on the stop's compliance; free again
    for ``max_delay`` samples from a command away from the stop (methods 8.4).
    """
    if not runs:
        return []
    extremes = (min(float(np.min(r.record.y)) for r in runs),
                max(float(np.max(r.record.y)) for r in runs))
    # A command heads away from the stop on the far side of the middle of the angles seen.
    middle = 0.5 * (extremes[0] + extremes[1])
    out = []
    for run in runs:
        record = run.record
        delay = max(1, min(max_delay, model.delay_samples(run.dt)))
        code = holds_of(record, delay, rest, model, extremes)
        held = code != 0
        # Ringing on the stop after arriving: held from arrival for a window, until the
        # delayed command changes.
        window = stop_window(run.dt)
        delayed = np.r_[np.full(delay, np.nan), record.v[:-delay]]
        arrivals = np.flatnonzero(held[1:] & ~held[:-1]) + 1
        for first in arrivals:
            last = min(first + window, held.size)
            same = np.flatnonzero(delayed[first:last] != delayed[first])
            held[first:first + (same[0] if same.size else last - first)] = True
        # Leaving a stop: from a command away from the stop the joint is at, and for the
        # longest delay considered, whether and when the joint leaves is the timing words'
        # evidence (a model's shorter dead time would otherwise leave only the longer one's
        # samples to judge).
        changes = np.flatnonzero(record.v[1:] != record.v[:-1]) + 1
        away = model.rate(record.v[changes]) * np.where(record.y[changes] > middle, -1.0, 1.0)
        for change in changes[(away > 0.0) & np.isin(code[changes], (1, 3))]:
            held[change:change + max_delay + 1] = False
        # Residual i is the increment ending at sample start + 1 + i.
        out.append(replace(run, free=~held[run.start + 1:]))
    return out


def _plays_at_stops(model: JointModel) -> bool:
    return model.angle_limits is not None and isinstance(model.effect(Backlash.name), Backlash) \
        and model.effect(AngleDependentVelocity.name) is None \
        and model.effect(Oscillation.name) is None


def _play_at_stops(model: JointModel, run: Run) -> FloatArray:
    """One-step increments with backlash where the actuator, not the sensor, meets the stops."""
    record = run.record
    play = model.effect(Backlash.name)
    assert isinstance(play, Backlash) and model.angle_limits is not None
    half = 0.5 * play.play
    speed = speed_profile(model, record.v, run.dt, v_before=float(record.v[0]),
                          exogenous=run.exogenous)[run.start + 1:]
    increment = run.dt * speed
    offset = bounded_cumsum(0.0, -increment, -half, half)
    previous = record.y[run.start:-1]
    # The sensor reads the actuator plus the play's offset, and the actuator stops at the
    # stops: pushed against one, the sensor stays the offset short of it.
    low, high = model.angle_limits
    after = offset[1:]
    predicted = np.clip(previous + increment + np.diff(offset), np.maximum(low, low + after),
                        np.minimum(high, high + after))
    return predicted - previous


def block_sums(residuals: Sequence[FloatArray], size: int) -> FloatArray:
    """Return the squared residual summed over whole blocks of ``size`` samples, run by run."""
    sums = []
    for series in residuals:
        squared = series * series
        whole = squared.size // size
        if whole:
            sums.append(squared[:whole * size].reshape(whole, size).sum(axis=1))
    return np.concatenate(sums) if sums else np.zeros(0)

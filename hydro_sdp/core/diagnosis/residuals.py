"""Runs, simulation error and the velocity residual of the discrepancy workflow (methods 8.1)."""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from typing import Sequence

from hydro_sdp.core.arrays import FloatArray
from hydro_sdp.core.identification.evaluation import record_mae
from hydro_sdp.core.identification.segmentation import check_record
from hydro_sdp.core.model.effects import AngleDependentVelocity, Backlash, Oscillation
from hydro_sdp.core.model.exogenous_signals import Exogenous, exogenous_of
from hydro_sdp.core.model.joint_model import JointModel
from hydro_sdp.core.model.records import Record
from hydro_sdp.core.model.simulation import bounded_cumsum, one_step_increments, speed_profile
import numpy as np

#: A candidate must remove at least this share of the squared velocity residual.
MIN_GAIN = 0.02
#: Length of the blocks residuals are summed over (and the shortest bootstrap block), s.
BLOCK_SECONDS = 1.0


@dataclass(frozen=True, eq=False)
class Run:
    """
    A record with the sample it is simulated from.

    Parameters
    ----------
    record : Record
        Measured record.
    dt : float
        Its sample period, s.
    start : int
        First sample at which the joint's state is settled.

    """

    record: Record
    dt: float
    start: int

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

    Parameters
    ----------
    records : sequence of Record
        Measured records.
    max_delay : float
        Largest delay considered, s.
    settle : float
        Shortest hold, s (0: every delayed command known is enough: the held-out runs
        a candidate is judged on, where a short run's first seconds count).

    Returns
    -------
    list[Run]
        One run per record.

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
        out.append(np.diff(run.record.y[run.start:]) - predicted)
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

"""
Signals beyond a joint's own command and angle, and the effects that use them (methods 3.6).

:func:`exogenous_of` gives a record's load, other joints' speeds and key;
:func:`exogenous_factor` is the speed factor of ``flow_sharing`` and ``load_dependence``.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import PurePath

from hydro_sdp.core.arrays import FloatArray
from hydro_sdp.core.errors import DataError
from hydro_sdp.core.model.joint_model import JointModel
from hydro_sdp.core.model.pump_and_load import FlowSharing, LoadDependence
from hydro_sdp.core.model.records import Record
from hydro_sdp.core.model.timing import SamplePeriod
import numpy as np

#: Window the other joints' speeds are averaged over, s.
SMOOTHING = 0.1
#: Smallest speed factor of ``load_dependence`` with a measured load.
MIN_LOAD_FACTOR = 0.05


@dataclass(frozen=True, eq=False)
class Exogenous:
    """
    A record's signals beyond its own command and angle, as the simulation uses them.

    Parameters
    ----------
    load : FloatArray or None
        Measured load at each sample, load units.
    other_speeds : FloatArray or None
        Other joints' speeds over the interval ending at each sample, deg/s, ``(n, joints)``.
    key : str
        The record's key (:func:`record_key`).

    """

    load: FloatArray | None = None
    other_speeds: FloatArray | None = None
    key: str = ''

    def check(self, samples: int) -> None:
        """Refuse signals not aligned with ``samples`` commands."""
        for name, values in (('load', self.load), ('other_speeds', self.other_speeds)):
            if values is not None and values.shape[0] != samples:
                raise DataError(f'{name} has {values.shape[0]} samples, the commands {samples}')


def record_key(record: Record) -> str:
    """Return the name of a record's own factors: source folder name, joint and start (s)."""
    start = record.since_start(float(record.t[0])) if len(record) else 0.0
    source = PurePath(record.source).name if record.source else 'record'
    return f'{source} {record.joint} at {start:.3f} s'


def smoothed_speeds(angles: FloatArray, dt: SamplePeriod,
                    t: FloatArray | None = None) -> FloatArray:
    """Return each column's speed over each sample interval, deg/s (:data:`SMOOTHING` s mean)."""
    angles = np.asarray(angles, dtype=np.float64).reshape(len(angles), -1)
    n = angles.shape[0]
    if n < 2:
        return np.zeros_like(angles)
    width = max(1, int(round(SMOOTHING / dt)))
    index = np.arange(n)
    behind = np.maximum(index - width, 0)
    if t is None:
        span = np.maximum(index - behind, 1) * dt
    else:
        stamps = np.asarray(t, dtype=np.float64)
        span = np.where(index > behind, stamps - stamps[behind], dt)
    return (angles - angles[behind]) / span[:, None]


def exogenous_of(record: Record, dt: SamplePeriod | None = None) -> Exogenous:
    """Return a record's load, other joints' speeds and key for the simulation."""
    speeds = None
    if record.others is not None and record.others.shape[1] and len(record) > 1:
        speeds = smoothed_speeds(record.others, dt or record.sample_period, record.t)
    return Exogenous(record.load, speeds, record_key(record))


def summed_other_speeds(signals: Exogenous, start: int) -> FloatArray | None:
    """Return the other joints' speeds summed per increment from ``start``, deg/s, or None."""
    speeds = signals.other_speeds
    return None if speeds is None else np.abs(speeds).sum(axis=1)[start + 1:]


def load_factor(load: FloatArray, slope: float, reference: float, overrun: float = 0.0,
                onset: float = 0.0) -> FloatArray:
    """
    Return one direction's speed factor of ``load_dependence`` at a measured load (methods 3.6).

    ``load``: measured load at each sample, load units.
    ``slope``: relative speed change per load unit, 1/load unit.
    ``reference``: load at which the slope's factor is 1, load units.
    ``overrun``: growth of the squared factor per load unit beyond ``onset`` (signed), 1/load unit.
    ``onset``: load at which the overrunning begins, load units.
    Returns: factor per sample.
    """
    load = np.asarray(load, dtype=np.float64)
    linear = np.maximum(MIN_LOAD_FACTOR, 1.0 + slope * (load - reference))
    if overrun == 0.0:
        return linear
    return linear * np.sqrt(1.0 + np.maximum(0.0, overrun * (load - onset)))


def exogenous_factor(model: JointModel, speed: FloatArray,
                     exogenous: Exogenous | None = None) -> FloatArray | None:
    """
    Return the speed factor of the model's ``flow_sharing`` and ``load_dependence``.

    ``speed``: speed the map, the delays and the lag give at each sample, deg/s.
    ``exogenous``: the record's signals; None: no load signal, the other joints still.
    Returns: factor per sample, or None when the model has neither effect.
    """
    sharing = model.effect(FlowSharing.name)
    load = model.effect(LoadDependence.name)
    if sharing is None and load is None:
        return None
    exogenous = exogenous or Exogenous()
    exogenous.check(speed.size)
    factor = np.ones(speed.size)
    if isinstance(sharing, FlowSharing):
        demand = np.where(speed > 0.0, speed / sharing.full_positive,
                          -speed / sharing.full_negative)
        if exogenous.other_speeds is not None:
            others = exogenous.other_speeds
            demand = demand + (np.maximum(others, 0.0).sum(axis=1) / sharing.other_positive
                               - np.minimum(others, 0.0).sum(axis=1) / sharing.other_negative)
        factor = np.minimum(1.0, sharing.limit / np.maximum(demand, 1e-12))
    if isinstance(load, LoadDependence):
        if exogenous.load is not None:
            up = load_factor(exogenous.load, load.positive, load.reference,
                             load.overrun_positive, load.onset_positive) * \
                load.smooth_factor(exogenous.load, True) * \
                load.power_cap(exogenous.load, speed, True)
            down = load_factor(exogenous.load, load.negative, load.reference,
                               load.overrun_negative, load.onset_negative) * \
                load.smooth_factor(exogenous.load, False) * \
                load.power_cap(exogenous.load, speed, False)
        else:
            up_factor, down_factor = load.record_factors(exogenous.key)
            up, down = np.full(speed.size, up_factor), np.full(speed.size, down_factor)
        factor = factor * np.where(speed > 0.0, up, np.where(speed < 0.0, down, 1.0))
    return factor

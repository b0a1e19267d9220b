"""Effects that need signals of a shared pump and a measured load (methods 3.6)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

from hydro_sdp.core.arrays import FloatArray
from hydro_sdp.core.errors import ModelFileError
import numpy as np


@dataclass(frozen=True)
class FlowSharing:
    """
    Speed cut when other joints draw on the same pump: ``w min(1, limit / demands)`` (methods 3.6).

    Parameters
    ----------
    limit : float
        Pump flow in full demands of this joint (> 0).
    full_positive, full_negative : float
        Speed of this joint in each direction that counts as one full demand, deg/s (> 0).
    other_positive, other_negative : float
        Speed of the other joints per direction that counts as one full demand, deg/s (> 0).

    """

    name: ClassVar[str] = 'flow_sharing'
    limit: float
    full_positive: float
    full_negative: float
    other_positive: float
    other_negative: float

    def __post_init__(self) -> None:
        for label in ('limit', 'full_positive', 'full_negative', 'other_positive',
                      'other_negative'):
            value = getattr(self, label)
            if not (np.isfinite(value) and value > 0.0):
                raise ModelFileError(f"key 'effects.flow_sharing.{label}': must be > 0, "
                                     f'got {value}')


def power_allowed(load: FloatArray, limit: float, offset: float) -> FloatArray:
    """
    Return the speed a power-limited pump allows, ``limit / (load + offset)`` (inf where <= 0).

    ``load``: measured load, load units.
    ``limit``: the cap, speed x load unit.
    ``offset``: load added to the measured one (the pump's margin above the load pressure).
    Returns: the speed allowed (the unit of ``limit`` over load units).
    """
    pressure = load + offset
    return np.where(pressure > 0.0, limit / np.maximum(pressure, 1e-12), np.inf)


@dataclass(frozen=True)
class LoadDependence:
    """
    Speed scaled by the load, each direction on its own (methods 3.6).

    A record without a load signal takes the factors fitted to it by key; others keep 1.

    Attributes
    ----------
    positive, negative : float
        Relative speed change per load unit in each direction, 1/load unit.
    reference : float
        Load at which the map holds, load units.
    record_positive, record_negative : tuple[float, ...]
        Speed factor of each of those records per direction (> 0).
    overrun_positive, overrun_negative : float
        Growth of the squared factor per load unit beyond the onset, 1/load unit (0: none).
    onset_positive, onset_negative : float
        Load at which the load begins to overrun in each direction, load units.
    knots : tuple[float, ...]
        Loads of the smooth factor, strictly increasing (two or more), or empty.
    factors_positive, factors_negative : tuple[float, ...]
        The smooth factor at each knot in each direction (> 0).
    limit_positive, limit_negative : float
        The pump's power cap in each direction, deg/s x load unit (0: none).
    limit_offset_positive, limit_offset_negative : float
        Load added to the measured one where the cap acts, load units.

    """

    name: ClassVar[str] = 'load_dependence'
    positive: float = 0.0
    negative: float = 0.0
    reference: float = 0.0
    records: tuple[str, ...] = ()
    record_positive: tuple[float, ...] = ()
    record_negative: tuple[float, ...] = ()
    overrun_positive: float = 0.0
    overrun_negative: float = 0.0
    onset_positive: float = 0.0
    onset_negative: float = 0.0
    knots: tuple[float, ...] = ()
    factors_positive: tuple[float, ...] = ()
    factors_negative: tuple[float, ...] = ()
    limit_positive: float = 0.0
    limit_negative: float = 0.0
    limit_offset_positive: float = 0.0
    limit_offset_negative: float = 0.0

    def __post_init__(self) -> None:
        key = "key 'effects.load_dependence"
        records = tuple(str(r) for r in self.records)
        up = tuple(float(x) for x in self.record_positive)
        down = tuple(float(x) for x in self.record_negative)
        if not len(up) == len(down) == len(records) or len(set(records)) != len(records):
            raise ModelFileError(f"{key}': records, record_positive and record_negative need "
                                 'one value per record, records named once')
        if not all(np.isfinite(x) and x > 0.0 for x in up + down):
            raise ModelFileError(f"{key}': record factors must be > 0")
        if not np.all(np.isfinite((self.positive, self.negative, self.reference,
                                   self.overrun_positive, self.overrun_negative,
                                   self.onset_positive, self.onset_negative))):
            raise ModelFileError(f"{key}': positive, negative, reference, overrun_* and "
                                 'onset_* must be finite')
        object.__setattr__(self, 'records', records)
        limits = (self.limit_positive, self.limit_negative, self.limit_offset_positive,
                  self.limit_offset_negative)
        if not np.all(np.isfinite(limits)) or min(limits[:2]) < 0.0:
            raise ModelFileError(f"{key}': limit_* must be finite and >= 0, limit_offset_* "
                                 'finite')
        object.__setattr__(self, 'record_positive', up)
        object.__setattr__(self, 'record_negative', down)
        knots = tuple(float(x) for x in self.knots)
        table = (tuple(float(x) for x in self.factors_positive),
                 tuple(float(x) for x in self.factors_negative))
        if knots or any(table):
            if len(knots) < 2 or any(len(side) != len(knots) for side in table):
                raise ModelFileError(f"{key}': knots, factors_positive and factors_negative "
                                     'need two or more values each, of equal number')
            if not np.all(np.isfinite(knots)) or np.any(np.diff(knots) <= 0.0):
                raise ModelFileError(f"{key}.knots': must be finite and strictly increasing")
            if not all(np.isfinite(x) and x > 0.0 for x in table[0] + table[1]):
                raise ModelFileError(f"{key}': factors_positive and factors_negative must "
                                     'be > 0')
        object.__setattr__(self, 'knots', knots)
        object.__setattr__(self, 'factors_positive', table[0])
        object.__setattr__(self, 'factors_negative', table[1])

    def smooth_factor(self, load: FloatArray, positive: bool) -> FloatArray:
        """Return the smooth factor ``f`` of one direction at the loads (1 without knots)."""
        load = np.asarray(load, dtype=np.float64)
        if not self.knots:
            return np.ones(load.shape)
        factors = self.factors_positive if positive else self.factors_negative
        return np.interp(load, self.knots, factors)

    def power_cap(self, load: FloatArray, speed: FloatArray, positive: bool) -> FloatArray:
        """Return the cap's factor of one direction at the loads and speeds (1: no cap)."""
        limit = self.limit_positive if positive else self.limit_negative
        load = np.asarray(load, dtype=np.float64)
        if limit <= 0.0:
            return np.ones(load.shape)
        offset = self.limit_offset_positive if positive else self.limit_offset_negative
        allowed = power_allowed(load, limit, offset)
        return np.minimum(1.0, allowed / np.maximum(np.abs(speed), 1e-12))

    def record_factors(self, key: str) -> tuple[float, float]:
        """Return the factors of the record called ``key`` (1, 1 when it has none)."""
        if key in self.records:
            index = self.records.index(key)
            return self.record_positive[index], self.record_negative[index]
        return 1.0, 1.0

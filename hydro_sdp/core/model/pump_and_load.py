"""
Effects that need signals beyond the joint's own: one pump shared, a measured load.

``flow_sharing`` and ``load_dependence`` of the model file (docs/interfaces.md
section 1.3); :mod:`hydro_sdp.core.model.exogenous_signals` turns a record's other
joints and load into the factors they put on the speed, and
:mod:`hydro_sdp.core.model.effects` lists them with the other effects.

"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

from hydro_sdp.core.arrays import FloatArray
from hydro_sdp.core.errors import ModelFileError
import numpy as np


@dataclass(frozen=True)
class FlowSharing:
    """
    Speed cut when other joints draw on the same pump (a shared pump-flow limit).

    Demands are normalised: the joint's own is ``w / full_positive`` or
    ``-w / full_negative`` (1 at its top speed in that direction, where one
    joint alone takes the whole pump), the other joints' ``sum_j (s_j+ / other_positive + s_j- /
    other_negative)`` with ``s_j+`` and ``s_j-`` the measured speed of other joint
    ``j`` in its positive and negative direction (deg/s, from the record's
    ``others``, smoothed over 0.1 s; a joint lowered by gravity draws less flow
    than one lifted). The speed becomes
    ``w min(1, limit / (own demand + other joints' demand))``: when the demands
    add up to more than the pump's ``limit``, every joint gets its share. The
    full speeds are set to the model's top speeds at the commands recorded, so
    that ``limit`` reads in full demands of this joint.

    Parameters
    ----------
    limit : float
        Pump flow in full demands of this joint (> 0; >= 1 leaves the joint alone
        as fast as its map says).
    full_positive, full_negative : float
        Speed of this joint in each direction that counts as one full demand, deg/s (> 0).
    other_positive, other_negative : float
        Speed of the other joints in their positive and negative directions that
        counts as one full demand, deg/s (> 0).

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
    Return the speed a power-limited pump allows at each load: ``limit / (load + offset)``.

    No cap (infinity) where ``load + offset <= 0``.

    Parameters
    ----------
    load : FloatArray
        Measured load, load units.
    limit : float
        The cap, speed x load unit.
    offset : float
        Load added to the measured one (the pump's margin above the load pressure).

    Returns
    -------
    FloatArray
        The speed allowed (the unit of ``limit`` over load units).

    """
    pressure = load + offset
    return np.where(pressure > 0.0, limit / np.maximum(pressure, 1e-12), np.inf)


@dataclass(frozen=True)
class LoadDependence:
    """
    Speed scaled by the load, each direction on its own (payload, digging force).

    With a measured load ``L`` (the record's ``load``, e.g. the signed load
    pressure of the cylinder in bar) the speed ``w`` becomes
    ``w max(0.05, 1 + k (L - reference)) sqrt(1 + max(0, g (L - onset))) f(L)``,
    with ``k``, ``g``, ``onset`` and ``f`` those of the direction of ``w``. The first
    factor is a speed change per load unit; the second is the overrunning load of a
    load-sensing valve: its pressure compensator holds the meter-in flow, so the
    load leaves the speed alone until it pulls the actuator along, and beyond
    ``onset`` the meter-out edge meters it, ``Q = Cd A(x) sqrt(2 dp / rho)`` with
    ``dp`` growing with the load: the same factor at every opening. The third is a
    smooth factor of any shape and either sign, ``f = interp(L, knots,
    factors_positive or factors_negative)`` held flat beyond the end knots (1 when
    there are no knots): the shape the data show, as the SDP analysis of the speed
    against the load draws it (a valve without pressure compensation, a pump whose
    power binds). A fourth factor caps the speed where the pump's power binds:
    ``min(1, limit / ((L + offset) |w|))``, with ``limit`` and ``offset`` those of the
    direction of ``w`` (no cap where ``limit`` is 0 or ``L + offset <= 0``): a
    pump whose torque limiter holds flow x pressure at its power ``P`` gives at most
    ``Q = P / p``, its pressure ``p`` the load pressure plus its load-sensing margin,
    so the speed the pump allows falls as ``1 / (L + margin)`` and caps fast commands
    while slow ones, whose flow stays below it, keep their speed (a factor of the load
    alone would slow both alike). A record without a load signal takes the factors fitted to it by
    name (``records``, with ``record_positive`` and ``record_negative``); other
    records keep factor 1.

    Parameters
    ----------
    positive, negative : float
        Relative speed change per load unit in each direction, 1/load unit.
    reference : float
        Load at which the map holds, load units.
    records : tuple[str, ...]
        Keys of records (:func:`~.exogenous_signals.record_key`) with fitted factors.
    record_positive, record_negative : tuple[float, ...]
        Speed factor of each of those records per direction (> 0).
    overrun_positive, overrun_negative : float
        ``g`` in each direction, 1/load unit: the squared speed factor grows by
        ``|g|`` per load unit beyond the onset (``g < 0``: as the load falls
        below it); 0 leaves the direction alone.
    onset_positive, onset_negative : float
        Load at which the load begins to overrun in each direction, load units.
    knots : tuple[float, ...]
        Loads of the smooth factor, load units, strictly increasing (two or more), or
        empty for none.
    factors_positive, factors_negative : tuple[float, ...]
        The smooth factor at each knot in each direction (> 0).
    limit_positive, limit_negative : float
        The pump's power cap in each direction, deg/s x load unit (>= 0; 0: none).
    limit_offset_positive, limit_offset_negative : float
        Load added to the measured one where the cap acts (the pump's margin above the
        load pressure), load units.

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

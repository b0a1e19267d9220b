"""
Records: aligned samples of one joint (time s, command in its units, angle degrees).

Times in messages count from the record's ``origin`` (the start of its bag);
:func:`split_at_gaps` cuts a record where its stamps jump (methods 2.6).
"""

from __future__ import annotations

from dataclasses import dataclass
import math

from typing import Sequence

from hydro_sdp.core.arrays import FloatArray
from hydro_sdp.core.errors import DataError
from hydro_sdp.core.model.sample_period import period_of_stamps
from hydro_sdp.core.model.timing import SamplePeriod
import numpy as np

#: Fewest samples a piece cut at a gap must have to be kept (what identification needs).
MIN_PIECE_SAMPLES = 50


@dataclass(frozen=True, eq=False)
class Record:
    """
    Time series of one joint's command and angle.

    Parameters
    ----------
    t : FloatArray
        Sample times, s, strictly increasing.
    v : FloatArray
        Command applied at each sample (held until the next), input units.
    y : FloatArray
        Measured angle at each sample, degrees.
    joint : str
        Joint name.
    source : str
        Where the record came from (a bag path), for messages.
    origin : float or None
        Time messages count from, s (the start of the bag); default: ``t[0]``.
    load : FloatArray or None
        Measured load at each sample (its own units, e.g. bar), or None.
    others : FloatArray or None
        Angles of the other joints at each sample, degrees, shape ``(n, joints)``, or None.
    other_joints : tuple[str, ...]
        Names of the columns of ``others``.

    See Also
    --------
    identify : a model from records.
    evaluate : a model's simulation error on records.

    Examples
    --------
    >>> import numpy as np
    >>> from hydro_sdp import Record
    >>> t = np.arange(0.0, 2.0, 0.01)
    >>> record = Record(t, np.where(t < 0.5, 0.0, 4.0), np.zeros(t.size), joint='j2')
    >>> len(record), record.sample_period
    (200, 0.01)

    """

    t: FloatArray
    v: FloatArray
    y: FloatArray
    joint: str = ''
    source: str = ''
    origin: float | None = None
    load: FloatArray | None = None
    others: FloatArray | None = None
    other_joints: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        arrays = {}
        for name in ('t', 'v', 'y'):
            values = np.asarray(getattr(self, name), dtype=np.float64)
            if values.ndim != 1:
                raise DataError(f'{self._label()}: {name} must be 1-D, got shape {values.shape}')
            arrays[name] = values
            object.__setattr__(self, name, values)
        if self.origin is not None and not math.isfinite(self.origin):
            raise DataError(f'{self._label()}: origin must be finite, got {self.origin}')
        lengths = {name: values.size for name, values in arrays.items()}
        if len(set(lengths.values())) != 1:
            raise DataError(f'{self._label()}: lengths differ (t, v, y: '
                            f"{lengths['t']}, {lengths['v']}, {lengths['y']})")
        for name, what in (('t', 'time'), ('v', 'command'), ('y', 'angle')):
            bad = np.flatnonzero(~np.isfinite(arrays[name]))
            if bad.size:
                raise DataError(f'{self._label()}: {bad.size} {what} samples are NaN or '
                                f'infinite (first at sample {bad[0]})')
        steps = np.diff(arrays['t'])
        backwards = np.flatnonzero(steps <= 0.0)
        if backwards.size:
            k = int(backwards[0])
            kind = 'repeat' if steps[k] == 0.0 else 'go backwards'
            since = arrays['t'][k + 1] - (arrays['t'][0] if self.origin is None else self.origin)
            raise DataError(f'{self._label()}: time stamps {kind} at sample {k + 1} '
                            f'({since:.6f} s from the start), {backwards.size} times in all')
        self._check_exogenous(arrays['t'].size)

    def _check_exogenous(self, n: int) -> None:
        """Validate ``load`` and ``others``: aligned with ``t`` and finite."""
        if self.load is not None:
            load = np.asarray(self.load, dtype=np.float64)
            if load.shape != (n,):
                raise DataError(f'{self._label()}: load must have one value per sample '
                                f'({n}), got shape {load.shape}')
            object.__setattr__(self, 'load', load)
        names = tuple(str(name) for name in self.other_joints)
        object.__setattr__(self, 'other_joints', names)
        if self.others is not None:
            others = np.asarray(self.others, dtype=np.float64)
            if others.ndim == 1:
                others = others[:, None]
            if others.ndim != 2 or others.shape[0] != n:
                raise DataError(f'{self._label()}: others must have one row per sample '
                                f'({n}), got shape {others.shape}')
            if len(names) not in (0, others.shape[1]):
                raise DataError(f'{self._label()}: others has {others.shape[1]} columns but '
                                f'{len(names)} other_joints are named')
            object.__setattr__(self, 'others', others)
        elif names:
            raise DataError(f'{self._label()}: other_joints named without others')
        for name, what in (('load', 'load'), ('others', 'other-joint angle')):
            values = getattr(self, name)
            if values is not None:
                bad = np.flatnonzero(~np.isfinite(values).reshape(values.shape[0], -1)
                                     .all(axis=1))
                if bad.size:
                    raise DataError(f'{self._label()}: {bad.size} {what} samples are NaN or '
                                    f'infinite (first at sample {bad[0]})')

    def since_start(self, t: float) -> float:
        """Time ``t`` (s) counted from the record's origin (the start of the bag), for messages."""
        if self.origin is not None:
            return float(t - self.origin)
        return float(t - self.t[0]) if self.t.size else float(t)

    def _label(self) -> str:
        parts = [part for part in (self.source, self.joint and f'joint {self.joint}') if part]
        return ' '.join(parts) or 'record'

    def __len__(self) -> int:
        """Return the number of samples."""
        return int(self.t.size)

    @property
    def sample_period(self) -> SamplePeriod:
        """Nominal spacing of the time stamps, s (:func:`.sample_period.period_of_stamps`)."""
        if self.t.size < 2:
            raise DataError(f'{self._label()}: needs at least two samples for a sample period')
        return SamplePeriod(period_of_stamps(self.t))

    @property
    def duration(self) -> float:
        """Time from the first to the last sample, s."""
        return float(self.t[-1] - self.t[0]) if self.t.size else 0.0

    def window(self, start: int, stop: int) -> Record:
        """Return samples ``start:stop`` as a new record."""
        return Record(self.t[start:stop], self.v[start:stop], self.y[start:stop],
                      self.joint, self.source, self._origin(),
                      None if self.load is None else self.load[start:stop],
                      None if self.others is None else self.others[start:stop],
                      self.other_joints)

    def _origin(self) -> float | None:
        if self.origin is not None:
            return self.origin
        return float(self.t[0]) if self.t.size else None


@dataclass(frozen=True)
class Gap:
    """
    A hole in a record's time stamps.

    Parameters
    ----------
    t : float
        Time of the last sample before the hole, s from the start of the record's bag.
    length : float
        Spacing of the samples either side, s.
    sample : int
        Index of the first sample after the hole, in the record that was split.

    """

    t: float
    length: float
    sample: int


@dataclass(frozen=True, eq=False)
class Pieces:
    """
    A record cut at the holes in its time stamps.

    Attributes
    ----------
    records : tuple[Record, ...]
        The pieces kept, in time order.
    dropped : int
        Samples left out in pieces too short to keep.

    """

    records: tuple[Record, ...]
    gaps: tuple[Gap, ...]
    dropped: int = 0

    @property
    def count(self) -> int:
        """Return the number of pieces kept."""
        return len(self.records)

    def describe(self) -> str:
        """One line for reports: how many pieces, and where the holes were."""
        holes = ', '.join(f'{gap.length:.3f} s at {gap.t:.3f} s' for gap in self.gaps)
        text = f'{self.count} piece{"s" if self.count != 1 else ""}'
        if self.gaps:
            text += f' (gaps of {holes})'
        if self.dropped:
            text += f', {self.dropped} samples in too short pieces left out'
        return text


def split_at_gaps(record: Record, *, max_gap: float = 3.0,
                  min_samples: int = MIN_PIECE_SAMPLES) -> Pieces:
    """
    Cut a record where its time stamps jump by more than ``max_gap`` sample periods (methods 2.6).

    The period is the record's median spacing; pieces keep its joint, source and origin.

    ``max_gap``: largest spacing kept inside one piece, in sample periods (> 1).
    ``min_samples``: fewest samples a piece cut from the record needs to be kept (>= 1).
    Raises DataError when every piece is too short.
    """
    if not (math.isfinite(max_gap) and max_gap > 1.0):
        raise DataError(f'max_gap must be a number of sample periods above 1, got {max_gap}')
    if min_samples < 1:
        raise DataError(f'min_samples must be at least 1, got {min_samples}')
    if len(record) < 3:
        return Pieces((record,), ())
    steps = np.diff(record.t)
    # The nominal period, as every later check of the pieces uses: a spacing a hair above
    # max_gap nominal periods but below max_gap median spacings is cut here, not refused there.
    period = record.sample_period
    cuts = np.flatnonzero(steps > max_gap * period) + 1
    if cuts.size == 0:
        return Pieces((record,), ())
    gaps = tuple(Gap(record.since_start(float(record.t[k - 1])), float(steps[k - 1]), int(k))
                 for k in cuts.tolist())
    bounds = [0] + cuts.tolist() + [len(record)]
    kept = []
    dropped = 0
    for start, stop in zip(bounds[:-1], bounds[1:]):
        if stop - start >= min_samples:
            kept.append(record.window(start, stop))
        else:
            dropped += stop - start
    pieces = Pieces(tuple(kept), gaps, dropped)
    if not kept:
        raise DataError(f'{record._label()}: cut at {len(gaps)} gaps in the time stamps, every '
                        f'piece is shorter than {min_samples} samples ({pieces.describe()})')
    return pieces


def split_records(records: Sequence[Record], *, max_gap: float = 3.0,
                  min_samples: int = MIN_PIECE_SAMPLES) -> tuple[list[Record], list[Pieces]]:
    """Cut every record at its gaps (:func:`split_at_gaps`) and pool the pieces."""
    splits = [split_at_gaps(record, max_gap=max_gap, min_samples=min_samples)
              for record in records]
    return [piece for split in splits for piece in split.records], splits

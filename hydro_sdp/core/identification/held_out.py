"""
Held-out judgement: the folds, the error and the rule that every choice on data follows.

The reasoning is in docs/methods.md section 16.

"""

from __future__ import annotations

from dataclasses import dataclass
import math
from typing import Hashable, Protocol, Sequence

from hydro_sdp.core.arrays import FloatArray, IntArray
from hydro_sdp.core.identification.evaluation import first_compared
from hydro_sdp.core.model.exogenous_signals import Exogenous
from hydro_sdp.core.model.joint_model import JointModel
from hydro_sdp.core.model.records import Record
from hydro_sdp.core.model.timing import SamplePeriod
from hydro_sdp.core.model.windows import simulate_windows
import numpy as np

#: Windows long records are cut into, s: each simulated afresh from the measured angle.
WINDOW_SECONDS = 2.0
#: The tie band's floor: a richer candidate must lower the held-out error by this share of
#: the simpler one's at least.
MARGIN = 0.05
#: Most folds of :func:`deal`.
MAX_FOLDS = 4


@dataclass(frozen=True)
class Unit:
    """
    What :func:`deal` deals: one experiment, record or stretch.

    Parameters
    ----------
    group : Hashable
        Units of one group (pieces of one recording) go to the same fold.
    level : float
        The held command of a step; NaN for anything else.
    side : int
        Sign of ``level`` against rest (-1, 0 or 1).

    """

    group: Hashable
    level: float = math.nan
    side: int = 0


def deal(units: Sequence[Unit], count: int | None = None) -> list[tuple[list[int], list[int]]]:
    """
    Deal units into folds whose test parts never ask a fit to extrapolate.

    ``units``: in a canonical order (the folds follow it).
    ``count``: number of folds; default: 2 to :data:`MAX_FOLDS`, as many as a side has inner levels
    held once.
    Returns: indices into ``units``; folds with an empty part are left out.
    """
    levels: dict[float, list[int]] = {}
    others: dict[Hashable, list[int]] = {}
    for index, unit in enumerate(units):
        if math.isfinite(unit.level):
            levels.setdefault(unit.level, []).append(index)
        else:
            others.setdefault(unit.group, []).append(index)
    inner: list[list[float]] = []
    for side in (-1, 1):
        ordered = sorted((level for level, members in levels.items()
                          if units[members[0]].side == side), key=abs)
        inside = set(ordered[1:-1])
        inner.append([level for level in sorted(levels)
                      if level in inside and len(levels[level]) == 1])
    if count is None:
        count = max(2, min(MAX_FOLDS, max(len(side) for side in inner)))
    fold = {}
    for members in levels.values():
        if len(members) > 1:
            fold.update({index: k % count for k, index in enumerate(members)})
    for held_once in inner:
        fold.update({levels[level][0]: k % count for k, level in enumerate(held_once)})
    for k, members in enumerate(others.values()):
        fold.update({index: k % count for index in members})
    out = []
    for f in range(count):
        test = [i for i in range(len(units)) if fold.get(i) == f]
        train = [i for i in range(len(units)) if fold.get(i) != f]
        if test and train:
            out.append((train, test))
    return out


#: In :func:`stretch_folds`, a stretch holds at most this share of the samples.
STRETCHES = 10
#: Most stretch folds (neighbouring stretches are held out together beyond).
MAX_STRETCH_FOLDS = 50


def stretch_folds(segment: IntArray, stretches: int = STRETCHES,
                  max_folds: int = MAX_STRETCH_FOLDS) -> IntArray:
    """
    Return the fold of each sample in time order: whole records, cut into tenths when longer.

    The reasoning is in docs/methods.md section 14.5.

    ``segment``: record of each sample, in time order (samples of one record consecutive).
    ``stretches``: a stretch is at most ``1 / stretches`` of the samples.
    Returns: fold of each sample, ``0..folds-1``.
    """
    segment = np.asarray(segment)
    n = segment.size
    longest = max(1, math.ceil(n / stretches))
    starts = np.r_[True, segment[1:] != segment[:-1]]
    index = np.arange(n)
    # Position of each sample within its record, then its stretch within the record.
    position = index - np.maximum.accumulate(np.where(starts, index, 0))
    piece = np.cumsum(starts | (position % longest == 0)) - 1
    pieces = int(piece[-1]) + 1 if n else 0
    return piece if pieces <= max_folds else (piece * max_folds) // pieces


class Scored(Protocol):
    """A record to score, with its sample period and its load and other joints' speeds."""

    @property
    def record(self) -> Record:
        """Return the measured record."""

    @property
    def dt(self) -> SamplePeriod:
        """Return its sample period, s."""

    @property
    def exogenous(self) -> Exogenous:
        """Return its load and other joints' speeds."""

    @property
    def free_samples(self) -> np.ndarray | None:
        """Return whether each sample is scored (None: all)."""


class WindowErrors:
    """Simulation errors of models over held-out records, over windows, each simulation once."""

    def __init__(self, runs: Sequence[Scored]) -> None:
        self.runs = runs
        self._cache: dict[tuple[int, int, int, float | None], float] = {}
        self._models: dict[int, JointModel] = {}

    def _error(self, model: JointModel, index: int, start: int, seconds: float | None) -> float:
        key = (id(model), index, start, seconds)
        if key not in self._cache:
            # Holding the model keeps its id from being reused while it is cached.
            self._models[id(model)] = model
            run = self.runs[index]
            record = run.record
            width = len(record) if seconds is None else max(1, int(round(seconds / run.dt)))
            simulated = simulate_windows(model, record.v, record.y, run.dt,
                                         list(range(start, len(record) - 1, width)),
                                         v_before=float(record.v[0]), exogenous=run.exogenous)
            error = np.abs(record.y[start:] - simulated[start:])
            # Samples a run marks as not free (held at a stop, stalled) are not scored.
            free = run.free_samples
            kept = None if free is None else free[start:]
            self._cache[key] = float(np.mean(error if kept is None or not kept.any()
                                             else error[kept]))
        return self._cache[key]

    def compare(self, models: Sequence[JointModel],
                seconds: float | None = WINDOW_SECONDS) -> list[float]:
        """Return each model's mean absolute simulation error, averaged per record, deg."""
        return self.per_record(models, seconds).mean(axis=0).tolist()

    def per_record(self, models: Sequence[JointModel],
                   seconds: float | None = WINDOW_SECONDS) -> FloatArray:
        """Return the errors of :meth:`compare` per record (rows) and model (columns), deg."""
        errors = np.zeros((len(self.runs), len(models)))
        for i, run in enumerate(self.runs):
            start = max(first_compared(model, run.dt, run.record) for model in models)
            for j, model in enumerate(models):
                errors[i, j] = self._error(model, i, start, seconds)
        return errors


@dataclass(frozen=True)
class Judgement:
    """
    Held-out errors of candidates over the same folds, and the one :func:`judge` chose.

    Attributes
    ----------
    errors : tuple[tuple[float, ...], ...]
        Per fold, each candidate's mean absolute error on the fold's test part, degrees (NaN: not
        scored).
    weights : tuple[float, ...]
        Samples of each fold's test part.
    chosen : int
        Index of the candidate chosen (-1: none could be scored).
    bands : tuple[float, ...]
        Each candidate's tie band against the best, degrees (NaN where unscored).

    """

    names: tuple[str, ...]
    errors: tuple[tuple[float, ...], ...]
    weights: tuple[float, ...]
    chosen: int
    bands: tuple[float, ...]

    @property
    def pooled(self) -> tuple[float, ...]:
        """Return each candidate's error pooled over the folds, degrees (NaN: unscored)."""
        return tuple(_pooled(self.errors, self.weights, c) for c in range(len(self.names)))

    @property
    def best(self) -> int:
        """Return the index of the least pooled error (-1: none scored)."""
        pooled = self.pooled
        scored = [c for c, value in enumerate(pooled) if math.isfinite(value)]
        return min(scored, key=lambda c: (pooled[c], c)) if scored else -1

    def gain(self, candidate: int, against: int = 0) -> float:
        """Return the share of ``against``'s pooled error that ``candidate`` takes away."""
        pooled = self.pooled
        if not pooled[against] > 0.0:
            return 0.0
        return 1.0 - pooled[candidate] / pooled[against]

    def lower_on(self, candidate: int, against: int = 0) -> int:
        """Return on how many folds ``candidate`` errs less than ``against``."""
        return sum(row[candidate] < row[against] for row in self.errors)

    def rule(self) -> str:
        """Return the rule in words, for reports."""
        return (f'the least held-out error wins, unless a simpler candidate is within its tie '
                f'band ({100 * MARGIN:g} % of its own error, or one standard error of its '
                'per-fold difference if larger); then the simplest such')

    def verdict(self) -> str:
        """Return why the chosen candidate was chosen, with the figures."""
        if self.chosen < 0:
            return 'nothing could be scored'
        pooled, best = self.pooled, self.best
        name = self.names[self.chosen]
        if self.chosen == best:
            beaten = [f'{self.names[c]} +{pooled[c] - pooled[best]:.3g} > band '
                      f'{self.bands[c]:.3g}' for c in range(self.chosen)
                      if math.isfinite(pooled[c])]
            return f'{name}: the least held-out error' + (
                f' ({"; ".join(beaten)} deg)' if beaten else '')
        return (f'{name}: within its tie band of {self.names[best]} '
                f'(+{pooled[self.chosen] - pooled[best]:.3g} <= {self.bands[self.chosen]:.3g} '
                'deg); the simpler wins a tie')


def _pooled(errors: Sequence[Sequence[float]], weights: Sequence[float], c: int) -> float:
    column = np.array([row[c] for row in errors], dtype=float)
    w = np.asarray(weights, dtype=float)
    if column.size == 0 or not np.all(np.isfinite(column)) or not np.sum(w) > 0.0:
        return math.nan
    return float(np.sum(w * column) / np.sum(w))


def judge(names: Sequence[str], errors: Sequence[Sequence[float]],
          weights: Sequence[float]) -> Judgement:
    """
    Choose among candidates by their held-out errors: the one rule (methods 16).

    ``errors``: per fold, each candidate's mean absolute held-out error, degrees; a candidate with
    a NaN on any fold is not scored.
    ``weights``: samples of each fold's test part.
    """
    rows = tuple(tuple(float(e) for e in row) for row in errors)
    weights = tuple(float(w) for w in weights)
    partial = Judgement(tuple(names), rows, weights, -1, ())
    pooled, best = partial.pooled, partial.best
    bands = []
    chosen = -1
    for c in range(len(names)):
        if not math.isfinite(pooled[c]) or best < 0:
            bands.append(math.nan)
            continue
        differences = np.array([row[c] - row[best] for row in rows])
        spread = float(np.std(differences, ddof=1) / math.sqrt(differences.size)) \
            if differences.size > 1 else 0.0
        band = max(MARGIN * pooled[c], spread)
        bands.append(band)
        if chosen < 0 and pooled[c] - pooled[best] <= band:
            chosen = c
    return Judgement(tuple(names), rows, weights, chosen, tuple(bands))

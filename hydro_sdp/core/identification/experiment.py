"""
Experiments: the pieces of records a fit sees, cut to length and thinned to a sample budget.

The reasoning is in docs/methods.md section 2.3.

"""

from __future__ import annotations

from dataclasses import dataclass
import math
from typing import Sequence

from hydro_sdp.core.arrays import FloatArray
import numpy as np

#: Samples an experiment needs beyond its start to be worth fitting.
MIN_SAMPLES = 10


@dataclass(frozen=True, eq=False)
class Experiment:
    """
    One segment of a record, with command history before its start.

    Attributes
    ----------
    v : FloatArray
        Commands from the start of the history to the end.
    y : FloatArray
        Angles alongside ``v``, degrees.
    start : int
        Index of the initial state: fits predict ``y[start + 1:]`` from ``y[start]``.
    kind : str
        ``step`` (one held command) or ``run``.
    level : float
        The held command of a step; NaN for a run.
    t0 : float
        Record time of ``y[start]``, s.

    """

    v: FloatArray
    y: FloatArray
    start: int
    kind: str
    level: float
    t0: float
    source: str = ''

    @property
    def samples(self) -> int:
        """Return the number of predicted samples."""
        return int(self.y.size - self.start - 1)


def split_long(experiments: Sequence[Experiment], max_samples: int,
               history: int) -> list[Experiment]:
    """
    Cut experiments longer than ``max_samples`` into consecutive pieces.

    ``max_samples``: longest piece, predicted samples.
    ``history``: command history kept before each piece, samples.
    Returns: the pieces, in order.
    """
    pieces = []
    for experiment in experiments:
        if experiment.samples <= max_samples:
            pieces.append(experiment)
            continue
        for start in range(experiment.start, experiment.y.size - 1, max_samples):
            first = max(start - history, 0)
            stop = min(start + max_samples + 1, experiment.y.size)
            if stop - start - 1 < MIN_SAMPLES:
                break
            pieces.append(Experiment(experiment.v[first:stop], experiment.y[first:stop],
                                     start - first, experiment.kind, experiment.level,
                                     experiment.t0, experiment.source))
    return pieces


def thin(experiments: Sequence[Experiment], max_samples: int) -> list[Experiment]:
    """Keep evenly spread experiments up to about ``max_samples`` predicted samples."""
    total = sum(e.samples for e in experiments)
    if total <= max_samples:
        return list(experiments)
    stride = math.ceil(total / max_samples)
    return list(experiments[::stride])


def thin_evenly(experiments: Sequence[Experiment], max_samples: int,
                rest: float) -> list[Experiment]:
    """
    Keep every k-th experiment of each kind and direction, up to about ``max_samples``.

    ``max_samples``: sample budget (predicted samples).
    Returns: all of them when within budget, else every k-th of each kind and direction, in their
    order: alternating directions are not thinned to one.
    """
    total = sum(e.samples for e in experiments)
    if total <= max_samples:
        return list(experiments)
    stride = math.ceil(total / max_samples)
    seen: dict[tuple[str, float], int] = {}
    out = []
    for experiment in experiments:
        side = float(np.sign(experiment.level - rest)) if math.isfinite(experiment.level) \
            else 0.0
        group = (experiment.kind, side)
        count = seen.get(group, 0)
        seen[group] = count + 1
        if count % stride == 0:
            out.append(experiment)
    return out

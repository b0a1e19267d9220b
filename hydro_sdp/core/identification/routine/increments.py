"""
One-step increments against the delayed command, and the delay that pairs them best.

The reasoning is in docs/methods.md section 15.3.

"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

from hydro_sdp.core.arrays import FloatArray
from hydro_sdp.core.errors import DataError
from hydro_sdp.core.identification.delay import DelayEstimate
from hydro_sdp.core.identification.experiment import Experiment
from hydro_sdp.core.model.sample_period import whole_samples_seconds
from hydro_sdp.core.model.timing import delayed_at, SamplePeriod
import numpy as np
from scipy.optimize import isotonic_regression


@dataclass(frozen=True, eq=False)
class Increments:
    """
    Angle increments and the delayed commands that drove them.

    Parameters
    ----------
    command : FloatArray
        ``v_{k-tau}`` of every increment, input units.
    increment : FloatArray
        ``y_k - y_{k-1}``, degrees.
    delay : int
        ``tau``, samples.

    """

    command: FloatArray
    increment: FloatArray
    delay: int

    @property
    def samples(self) -> int:
        """Return the number of increments."""
        return int(self.increment.size)


def increments_of(experiments: Sequence[Experiment], delay: int, *,
                  first: int = 0) -> Increments:
    """
    Pair every predicted increment of the experiments with its delayed command.

    ``first``: leave out samples before this index of each experiment (so that every candidate
    delay sees the same increments).
    """
    commands, increments = [], []
    for experiment in experiments:
        k = np.arange(max(experiment.start + 1, first, 1), experiment.y.size)
        commands.append(delayed_at(experiment.v, k, delay))
        increments.append(experiment.y[k] - experiment.y[k - 1])
    if not commands or sum(c.size for c in commands) == 0:
        raise DataError('no angle increments to identify from')
    return Increments(np.concatenate(commands), np.concatenate(increments), delay)


def monotone_share(increment: FloatArray, command: FloatArray) -> float:
    """Share of the increments' variance explained by the best monotone function of the command."""
    total = float(np.sum((increment - np.mean(increment)) ** 2))
    if total <= 0.0:
        return 0.0
    levels, inverse, counts = np.unique(command, return_inverse=True, return_counts=True)
    means = np.bincount(inverse, weights=increment) / counts
    fitted = isotonic_regression(means, weights=counts.astype(np.float64)).x
    return 1.0 - float(np.sum((increment - fitted[inverse]) ** 2)) / total


def _linear(increment: FloatArray, command: FloatArray) -> float:
    a, b = increment - np.mean(increment), command - np.mean(command)
    scale = float(np.sqrt(np.dot(a, a) * np.dot(b, b)))
    return float(np.dot(a, b)) / scale if scale > 0.0 else 0.0


def increment_delay(experiments: Sequence[Experiment], dt: SamplePeriod, *, max_delay: int,
                    rest: float) -> DelayEstimate:
    """
    Estimate the delay of routine operation from increments and delayed commands.

    ``experiments``: the runs, each with ``max_delay`` samples of command history.
    ``dt``: sample period, s.
    ``max_delay``: largest delay considered, samples.
    Returns: ``fit``: the delay of the largest monotone correlation ratio (:func:`monotone_share`;
    ``explained``, one value per delay 1..max_delay); ``xcorr``: that of the largest linear
    correlation; no onset and no valve lag.
    Raises DataError when the command never leaves rest.
    """
    base = increments_of(experiments, 0, first=max_delay)
    if not np.any(np.concatenate([e.v for e in experiments]) != rest):
        raise DataError('the command never leaves rest: nothing drives the joint')
    ratios, linear = np.zeros(max_delay), np.zeros(max_delay)
    for delay in range(1, max_delay + 1):
        command = increments_of(experiments, delay, first=max_delay).command
        ratios[delay - 1] = monotone_share(base.increment, command)
        linear[delay - 1] = _linear(base.increment, command)
    best = int(np.argmax(ratios)) + 1
    return DelayEstimate(samples=best, seconds=whole_samples_seconds(best, dt), fit=best,
                         onset=None, xcorr=int(np.argmax(linear)) + 1, explained=ratios)

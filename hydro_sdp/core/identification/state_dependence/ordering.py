"""
Re-ordering the samples by a state: the groups a state-dependent parameter is estimated over.

The reasoning is in docs/methods.md section 14.1.

"""

from __future__ import annotations

from dataclasses import dataclass

from hydro_sdp.core.arrays import FloatArray, IntArray
from hydro_sdp.core.errors import DataError
from hydro_sdp.core.identification.state_dependence.random_walk import group_stats, GroupStats
import numpy as np

#: Most groups a state is cut into (distinct values pooled beyond it).
MAX_GROUPS = 20_000


@dataclass(frozen=True, eq=False)
class Ordering:
    """
    Samples grouped by the value of a state, groups sorted by it.

    Attributes
    ----------
    samples : IntArray
        Indices of the samples that inform the parameter (regressor not zero), ascending.
    group : IntArray
        Group of each of those samples, ``0..M-1`` in increasing state.
    values : FloatArray
        State value of each group (the mean over its samples).

    """

    samples: IntArray
    group: IntArray
    values: FloatArray
    pooled: bool = False

    @property
    def groups(self) -> int:
        """Return the number of groups ``M``."""
        return int(self.values.size)

    def stats(self, z: FloatArray, x: FloatArray) -> GroupStats:
        """Return the per-group sums of ``z = x p + e`` over the ordered samples."""
        return group_stats(np.asarray(z)[self.samples], np.asarray(x)[self.samples],
                           self.group, self.groups)

    def at_samples(self, per_group: FloatArray, state: FloatArray) -> FloatArray:
        """
        Return a per-group quantity at every sample of the record set.

        Ordered samples take their group's value; the others (regressor zero) the
        value interpolated at their state.

        """
        out = np.interp(np.asarray(state, dtype=np.float64), self.values, per_group)
        out[self.samples] = np.asarray(per_group)[self.group]
        return out


def order_by_state(state: FloatArray, regressor: FloatArray, *,
                   max_groups: int | None = MAX_GROUPS) -> Ordering:
    """
    Group the informative samples by the value of a state.

    ``state``: the state at every sample.
    ``regressor``: the parameter's regressor at every sample (zero: the sample says nothing).
    ``max_groups``: pool neighbouring distinct values beyond this many groups; None: never.
    """
    state = np.asarray(state, dtype=np.float64)
    regressor = np.asarray(regressor, dtype=np.float64)
    if state.shape != regressor.shape:
        raise DataError(f'state and regressor differ in length ({state.size}, {regressor.size})')
    if not np.all(np.isfinite(state)):
        raise DataError('the state has NaN or infinite values')
    samples = np.flatnonzero(regressor != 0.0)
    if samples.size == 0:
        raise DataError('the regressor is zero at every sample')
    distinct, inverse, counts = np.unique(state[samples], return_inverse=True,
                                          return_counts=True)
    ordering = Ordering(samples, inverse, distinct)
    return ordering if max_groups is None else coarsened(ordering, max_groups, state)


def coarsened(ordering: Ordering, max_groups: int, state: FloatArray) -> Ordering:
    """
    Pool neighbouring groups of an ordering into about ``max_groups`` of equal sample count.

    ``max_groups``: most groups kept (>= 2); an ordering within it comes back as it is.
    ``state``: the state at every sample (for the pooled groups' mean values).
    """
    if ordering.groups <= max_groups:
        return ordering
    if max_groups < 2:
        raise DataError(f'max_groups must be at least 2, got {max_groups}')
    counts = np.bincount(ordering.group, minlength=ordering.groups)
    # Cut the cumulative count into max_groups equal shares, only between groups.
    ends = np.cumsum(counts)
    share = ends[-1] / max_groups
    pool = np.minimum((ends - 1) // share, max_groups - 1).astype(np.int64)
    _, pool = np.unique(pool, return_inverse=True)
    group = pool[ordering.group]
    sizes = np.bincount(group)
    values = np.bincount(group, weights=np.asarray(state, dtype=np.float64)[ordering.samples])
    return Ordering(ordering.samples, group, values / sizes, pooled=True)

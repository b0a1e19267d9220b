"""
One state-dependent parameter smoothed along its ordering, its NVR estimated or given.

The reasoning is in docs/methods.md section 14.3.

"""

from __future__ import annotations

from dataclasses import dataclass

from hydro_sdp.core.arrays import FloatArray
from hydro_sdp.core.identification.state_dependence.banded import (
    BandedFit, fit_banded, fit_flat, FlatFit, null_basis)
from hydro_sdp.core.identification.state_dependence.nvr import estimate_nvr, NvrEstimate
from hydro_sdp.core.identification.state_dependence.random_walk import GroupStats, inner, order_of
import numpy as np


@dataclass(frozen=True, eq=False)
class SmoothedParameter:
    """
    A parameter smoothed along the groups of one state.

    Attributes
    ----------
    kind : str
        ``rw`` or ``irw`` (``rw`` when the state has too few values for ``irw``).
    nvr : NvrEstimate
        The NVR used (estimated, or given with a NaN standard error).
    estimate : FloatArray
        Parameter per group.
    fit : BandedFit or FlatFit
        The banded fit (NVR > 0) or the flat one (NVR 0).

    """

    kind: str
    nvr: NvrEstimate
    estimate: FloatArray
    stats: GroupStats
    fit: BandedFit | FlatFit

    @property
    def sigma2(self) -> float:
        """Return the concentrated noise variance."""
        return self.fit.sigma2

    def variance(self) -> FloatArray:
        """Return the estimate's variance per group (``sigma^2`` included)."""
        if isinstance(self.fit, BandedFit):
            return self.fit.variance() * self.fit.sigma2
        basis = null_basis(self.stats.groups, self.kind)
        return self.fit.standard_error(basis) ** 2

    def standard_error(self) -> FloatArray:
        """Return the estimate's standard error per group."""
        return np.sqrt(self.variance())

    def degrees_of_freedom(self) -> float:
        """Return the smoother's equivalent degrees of freedom, ``trace`` of its hat matrix."""
        if isinstance(self.fit, FlatFit):
            return float(order_of(self.kind))
        return inner(self.stats.weight, self.fit.variance())


def smooth_parameter(stats: GroupStats, kind: str,
                     nvr: float | NvrEstimate | None = None) -> SmoothedParameter:
    """
    Smooth the parameter ``p`` of ``z = x p(state) + e`` along the groups of a state.

    ``stats``: sums of the observations per group
    (:meth:`~hydro_sdp.core.identification.state_dependence.ordering.Ordering.stats`).
    ``nvr``: NVR to use; None: estimate it by maximum likelihood.
    """
    if stats.groups <= order_of(kind):
        kind = 'rw'
        nvr = NvrEstimate(0.0, float('nan'), float('nan'), float('nan'))
    if nvr is None:
        nvr = estimate_nvr(stats, kind)
    elif not isinstance(nvr, NvrEstimate):
        nvr = NvrEstimate(float(nvr), float('nan'), float('nan'), float('nan'))
    if nvr.nvr == 0.0:
        flat = fit_flat(stats, kind)
        return SmoothedParameter(kind, nvr, flat.estimate, stats, flat)
    banded = fit_banded(stats, kind, nvr.nvr)
    return SmoothedParameter(kind, nvr, banded.estimate, stats, banded)

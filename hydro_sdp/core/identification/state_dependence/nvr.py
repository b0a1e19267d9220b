"""The NVR of a random-walk parameter by maximum likelihood (methods 14.3)."""

from __future__ import annotations

from dataclasses import dataclass
import math

from hydro_sdp.core.errors import DataError
from hydro_sdp.core.identification.state_dependence.banded import (
    fit_banded, fit_flat, penalty_bands)
from hydro_sdp.core.identification.state_dependence.random_walk import GroupStats
import numpy as np
from scipy.optimize import minimize_scalar

#: Range of ``log10(nvr * mean weight)`` searched: below it the walk is as good as flat
#: over 20 000 groups, and the banded equations stay well conditioned (``4 eps / 1e-10``).
LOG_RANGE = (-10.0, 4.0)
#: Points of the coarse scan.
SCAN_POINTS = 15
#: Step in ``ln nvr`` of the curvature's finite difference.
CURVATURE_STEP = 0.1
#: Least fall of ``-2 log L`` from the flat walk for a positive NVR: below it the data do
#: not tell the walk from a constant (a likelihood ratio within 1.0005), and the NVR
#: would be the rounding of sums (docs/methods.md section 14.3).
TIE = 1e-3


@dataclass(frozen=True)
class NvrEstimate:
    """
    The maximum-likelihood NVR.

    Parameters
    ----------
    nvr : float
        The estimate; 0 when the flat walk (no dependence) is the most likely.
    log_se : float
        Standard error of ``ln nvr`` (NaN at 0 or at the end of the range).
    neg2_log_likelihood : float
        ``-2 log L`` at the estimate.
    neg2_log_likelihood_flat : float
        ``-2 log L`` at zero NVR.
    at_limit : bool
        Whether the estimate is at the end of the searched range.

    """

    nvr: float
    log_se: float
    neg2_log_likelihood: float
    neg2_log_likelihood_flat: float
    at_limit: bool = False

    def interval(self, width: float = 2.0) -> tuple[float, float]:
        """Return ``nvr exp(-+ width se)``: the approximate interval of the estimate."""
        if self.nvr == 0.0 or not math.isfinite(self.log_se):
            return (self.nvr, self.nvr)
        return (self.nvr * math.exp(-width * self.log_se),
                self.nvr * math.exp(width * self.log_se))


def nvr_range(stats: GroupStats) -> tuple[float, float]:
    """Return the NVRs searched: :data:`LOG_RANGE` over the mean weight per group."""
    scale = stats.scale
    if not scale > 0.0:
        raise DataError('the regressor is zero at every sample')
    return 10.0 ** LOG_RANGE[0] / scale, 10.0 ** LOG_RANGE[1] / scale


def estimate_nvr(stats: GroupStats, kind: str) -> NvrEstimate:
    """
    Find the NVR that maximises the concentrated likelihood.

    ``stats``: sums of the observations per group.
    Returns: the estimate, its standard error in ``ln nvr`` and the likelihoods.
    """
    flat = fit_flat(stats, kind).neg2_log_likelihood
    low, high = (math.log(value) for value in nvr_range(stats))
    # The same for every trial NVR: built once.
    dd_bands = penalty_bands(stats.groups, kind)

    def cost(log_nvr: float) -> float:
        return fit_banded(stats, kind, math.exp(log_nvr), dd_bands=dd_bands).neg2_log_likelihood

    scan = np.linspace(low, high, SCAN_POINTS)
    values = np.array([cost(float(x)) for x in scan])
    best = int(np.argmin(values))
    left, right = scan[max(best - 1, 0)], scan[min(best + 1, scan.size - 1)]
    result = minimize_scalar(cost, bounds=(float(left), float(right)), method='bounded',
                             options={'xatol': 1e-3})
    log_nvr, neg2 = float(result.x), float(result.fun)
    if values[best] < neg2:
        log_nvr, neg2 = float(scan[best]), float(values[best])
    if flat <= neg2 + TIE:
        return NvrEstimate(0.0, math.nan, flat, flat)
    at_limit = log_nvr - low < 2.0 * CURVATURE_STEP or high - log_nvr < 2.0 * CURVATURE_STEP
    log_se = math.nan
    if not at_limit:
        h = CURVATURE_STEP
        curvature = (cost(log_nvr + h) - 2.0 * neg2 + cost(log_nvr - h)) / (h * h)
        if curvature > 0.0:
            log_se = math.sqrt(2.0 / curvature)
    return NvrEstimate(math.exp(log_nvr), log_se, neg2, flat, at_limit)

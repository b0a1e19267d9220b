"""
The recursive Kalman filter and fixed-interval smoother of a random-walk parameter.

The reasoning is in docs/methods.md section 14.1.

"""

from __future__ import annotations

from dataclasses import dataclass
import math

from hydro_sdp.core.arrays import FloatArray, IntArray
from hydro_sdp.core.errors import DataError
from hydro_sdp.core.identification.state_dependence.random_walk import transition
import numpy as np


@dataclass(frozen=True, eq=False)
class KalmanSmoothing:
    """
    What the filter and the smoother give, per group.

    Attributes
    ----------
    filtered : FloatArray
        Filtered parameter after each group's observations.
    variance : FloatArray
        Smoothed variance, normalised by ``sigma^2``.
    innovations : FloatArray
        One-step prediction errors, one per observation (in the sorted order).
    innovation_variance : FloatArray
        Their normalised variances ``f_k``.
    sigma2 : float
        Concentrated noise variance ``sum eps^2 / f / n``.
    neg2_log_likelihood : float
        ``-2 log L`` by the prediction-error decomposition.

    """

    filtered: FloatArray
    smoothed: FloatArray
    variance: FloatArray
    innovations: FloatArray
    innovation_variance: FloatArray
    sigma2: float
    neg2_log_likelihood: float

    @property
    def standard_error(self) -> FloatArray:
        """Return the standard error of the smoothed parameter."""
        return np.sqrt(self.variance * self.sigma2)


def kalman_smooth(z: FloatArray, x: FloatArray, group: IntArray, kind: str, nvr: float, *,
                  prior: float = 1e5) -> KalmanSmoothing:
    """
    Filter and smooth a random-walk parameter over observations sorted by group.

    ``z``: observations ``z_k = x_k p_{g(k)} + e_k``, sorted so that ``group`` never decreases.
    ``group``: group of each observation: ``0, 0, 1, 2, 2, ...`` (every group present).
    ``nvr``: noise variance ratio (>= 0).
    """
    z = np.asarray(z, dtype=np.float64)
    x = np.asarray(x, dtype=np.float64)
    group = np.asarray(group)
    steps = np.diff(group)
    if group.size == 0 or group[0] != 0 or np.any((steps != 0) & (steps != 1)):
        raise DataError('observations must be sorted by group, every group present')
    if not (math.isfinite(nvr) and nvr >= 0.0 and prior > 0.0):
        raise DataError(f'nvr must be >= 0 and prior > 0, got {nvr} and {prior}')
    F, G = transition(kind)
    Q = nvr * (G @ G.T)
    size = F.shape[0]
    groups = int(group[-1]) + 1
    a = np.zeros(size)
    P = prior * np.eye(size)
    predicted_a = np.zeros((groups, size))
    predicted_P = np.zeros((groups, size, size))
    filtered_a = np.zeros((groups, size))
    filtered_P = np.zeros((groups, size, size))
    innovations = np.zeros(z.size)
    variances = np.zeros(z.size)
    current = -1
    for k in range(z.size):
        g = int(group[k])
        if g != current:
            if current >= 0:
                filtered_a[current], filtered_P[current] = a, P
                a = F @ a
                P = F @ P @ F.T + Q
            predicted_a[g], predicted_P[g] = a, P
            current = g
        # Only the parameter (the first state) is observed.
        Ph = P[:, 0] * x[k]
        f = 1.0 + x[k] * Ph[0]
        eps = z[k] - x[k] * a[0]
        a = a + Ph * (eps / f)
        P = P - np.outer(Ph, Ph) / f
        innovations[k], variances[k] = eps, f
    filtered_a[current], filtered_P[current] = a, P
    smoothed_a = filtered_a.copy()
    smoothed_P = filtered_P.copy()
    for j in range(groups - 2, -1, -1):
        gain = filtered_P[j] @ F.T @ np.linalg.inv(predicted_P[j + 1])
        smoothed_a[j] = filtered_a[j] + gain @ (smoothed_a[j + 1] - predicted_a[j + 1])
        smoothed_P[j] = filtered_P[j] + gain @ (smoothed_P[j + 1] - predicted_P[j + 1]) @ gain.T
    sigma2 = float(np.sum(innovations ** 2 / variances) / z.size)
    neg2 = float(np.sum(np.log(variances)) + z.size * (math.log(2.0 * math.pi * sigma2) + 1.0))
    return KalmanSmoothing(filtered_a[:, 0], smoothed_a[:, 0], smoothed_P[:, 0, 0].copy(),
                           innovations, variances, sigma2, neg2)

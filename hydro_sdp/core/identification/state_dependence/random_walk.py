"""
Random-walk models of a parameter along an ordering, and the statistics a fit needs.

The reasoning is in docs/methods.md section 14.2.

"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from hydro_sdp.core.arrays import FloatArray, IntArray
from hydro_sdp.core.errors import ConfigurationError, DataError
import numpy as np

#: The random-walk families: random walk and integrated random walk.
TvpKind = Literal['rw', 'irw']
KINDS: tuple[TvpKind, ...] = ('rw', 'irw')
#: Rows of the difference operator of each family (order 1 and 2).
STENCILS: dict[str, tuple[float, ...]] = {'rw': (-1.0, 1.0), 'irw': (1.0, -2.0, 1.0)}


def inner(a: FloatArray, b: FloatArray) -> float:
    """Return ``sum(a * b)`` without BLAS."""
    return float(np.sum(np.multiply(a, b)))


def order_of(kind: str) -> int:
    """Return the order ``d`` of a family's difference operator (its diffuse states)."""
    if kind not in STENCILS:
        raise ConfigurationError(f"random-walk model must be 'rw' or 'irw', got {kind!r}")
    return len(STENCILS[kind]) - 1


def transition(kind: str) -> tuple[FloatArray, FloatArray]:
    """
    Return the state-space form ``(F, G)`` of a family (the walk's state is ``(p[, s])``).

    Returns: transition matrix ``F`` and noise input ``G`` (``x_{j+1} = F x_j + G eta``).
    """
    if order_of(kind) == 1:
        return np.ones((1, 1)), np.ones((1, 1))
    return np.array([[1.0, 1.0], [0.0, 1.0]]), np.array([[0.0], [1.0]])


def difference(values: FloatArray, kind: str) -> FloatArray:
    """Return ``D p``: the steps (``rw``) or second differences (``irw``) of ``values``."""
    return np.diff(np.asarray(values, dtype=np.float64), n=order_of(kind))


@dataclass(frozen=True, eq=False)
class GroupStats:
    """
    Sufficient statistics of the observations ``z_k = x_k p_{g(k)} + e_k``, per group.

    Attributes
    ----------
    weight : FloatArray
        ``sum x_k^2`` over each group's observations.
    moment : FloatArray
        ``sum x_k r_k`` over each group's observations.
    total : float
        ``sum r_k^2`` over all observations.

    """

    weight: FloatArray
    moment: FloatArray
    total: float
    count: int
    reference: float = 0.0

    @property
    def groups(self) -> int:
        """Return the number of groups ``M``."""
        return int(self.weight.size)

    @property
    def scale(self) -> float:
        """Return the mean weight per group (the information of one group)."""
        return float(np.mean(self.weight)) if self.weight.size else 0.0

    def residual_sum(self, estimate: FloatArray) -> float:
        """Return ``sum (z_k - x_k p_{g(k)})^2`` for the per-group ``estimate``."""
        return self.offset_residual_sum(np.asarray(estimate, dtype=np.float64) - self.reference)

    def offset_residual_sum(self, offset: FloatArray) -> float:
        """Return the squared residual of the parameter ``reference + offset``, per group."""
        return self.total - 2.0 * inner(offset, self.moment) + inner(offset * offset,
                                                                     self.weight)


def group_stats(z: FloatArray, x: FloatArray, group: IntArray, groups: int) -> GroupStats:
    """Sum the observations of each group."""
    z = np.asarray(z, dtype=np.float64)
    x = np.asarray(x, dtype=np.float64)
    if not (z.shape == x.shape == np.shape(group)):
        raise DataError(f'observations, regressors and groups differ in length '
                        f'({z.size}, {x.size}, {np.size(group)})')
    if not (np.all(np.isfinite(z)) and np.all(np.isfinite(x))):
        raise DataError('observations and regressors must be finite')
    squares = x * x
    power = float(np.sum(squares))
    reference = inner(x, z) / power if power > 0.0 else 0.0
    r = z - x * reference
    weight = np.bincount(group, weights=squares, minlength=groups).astype(np.float64)
    moment = np.bincount(group, weights=x * r, minlength=groups).astype(np.float64)
    return GroupStats(weight, moment, inner(r, r), int(z.size), reference)

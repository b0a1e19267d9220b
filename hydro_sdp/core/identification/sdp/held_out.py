"""
How much of the squared residual a state dependence removes on data it was not fitted to.

A state with many distinct values can index the samples almost one by one:
steps that each travel their own stretch of the stroke make the angle a
label of the step, and a parameter along the angle then fits each step's own
transient. In-sample, that looks like a strong dependence; on held-out data it
predicts nothing. The share reported for a dependence is therefore held out:
the term's samples, in time order, are cut into :data:`FOLDS` contiguous
folds; for each, the parameter is smoothed along the state (its NVR fixed) on
the other folds and predicts the held-out one at its state values (groups
without training data are filled by the walk), and the same is done with the
parameter held constant. The reduction is the held-out squared residual of the
constant less that of the smoothed parameter (negative: the dependence
predicts worse than a constant).

"""

from __future__ import annotations

from hydro_sdp.core.arrays import FloatArray
from hydro_sdp.core.identification.sdp.banded import fit_banded
from hydro_sdp.core.identification.sdp.ordering import Ordering
from hydro_sdp.core.identification.sdp.random_walk import GroupStats
import numpy as np

#: Contiguous folds of the held-out reduction.
FOLDS = 10


def held_out_reduction(z: FloatArray, x: FloatArray, ordering: Ordering, kind: str,
                       nvr: float, *, folds: int = FOLDS) -> float:
    """
    Return the held-out reduction in squared residual of a parameter following its state.

    Parameters
    ----------
    z : FloatArray
        The term's observations (its partial residual) at every sample.
    x : FloatArray
        Its regressor at every sample.
    ordering : Ordering
        Groups of the state.
    kind : str
        ``rw`` or ``irw``.
    nvr : float
        The walk's NVR (0: the parameter is constant, the reduction 0).
    folds : int
        Number of contiguous folds.

    Returns
    -------
    float
        Held-out squared residual with the parameter constant, less that with it
        following the state.

    """
    if nvr <= 0.0:
        return 0.0
    samples = ordering.samples
    zs = np.asarray(z, dtype=np.float64)[samples]
    xs = np.asarray(x, dtype=np.float64)[samples]
    n = zs.size
    if n < 2 * folds:
        return 0.0
    fold = (np.arange(n) * folds) // n
    groups = ordering.groups
    cell = fold * groups + ordering.group
    # Weight and moment of every (fold, group) in one pass.
    w_out = np.bincount(cell, weights=xs * xs, minlength=folds * groups).reshape(folds, groups)
    m_out = np.bincount(cell, weights=xs * zs, minlength=folds * groups).reshape(folds, groups)
    z_out = np.bincount(fold, weights=zs * zs, minlength=folds)
    n_out = np.bincount(fold, minlength=folds)
    weight, moment = w_out.sum(axis=0), m_out.sum(axis=0)
    total = float(np.sum(z_out))
    constants = np.zeros(folds)
    estimates = np.zeros((folds, groups))
    for f in range(folds):
        train_w, train_m = weight - w_out[f], moment - m_out[f]
        train = GroupStats(train_w, train_m, total - float(z_out[f]), n - int(n_out[f]))
        constants[f] = float(np.sum(train_m) / np.sum(train_w))
        estimates[f] = fit_banded(train, kind, nvr).estimate
    constant_squares = float(np.sum((zs - xs * constants[fold]) ** 2))
    smoothed_squares = float(np.sum((zs - xs * estimates[fold, ordering.group]) ** 2))
    return constant_squares - smoothed_squares

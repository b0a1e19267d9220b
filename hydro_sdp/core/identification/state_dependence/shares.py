"""
How much of the squared residual a state dependence removes on data it was not fitted to.

The reasoning is in docs/methods.md section 14.5.

"""

from __future__ import annotations

from hydro_sdp.core.arrays import FloatArray, IntArray
from hydro_sdp.core.identification.held_out import stretch_folds
from hydro_sdp.core.identification.state_dependence.banded import fit_banded, fit_flat
from hydro_sdp.core.identification.state_dependence.ordering import Ordering
from hydro_sdp.core.identification.state_dependence.random_walk import GroupStats
import numpy as np


def held_out_reduction(z: FloatArray, x: FloatArray, ordering: Ordering, kind: str,
                       nvr: float, segment: IntArray | None = None) -> float:
    """
    Return the held-out reduction in squared residual of a parameter following its state.

    ``z``: the term's observations (its partial residual) at every sample.
    ``x``: its regressor at every sample.
    ``nvr``: the walk's NVR (0: a constant, the reduction 0; for ``irw`` a line in the rank).
    ``segment``: record of every sample (None: one record).
    """
    if nvr <= 0.0 and kind == 'rw':
        return 0.0
    samples = ordering.samples
    zs = np.asarray(z, dtype=np.float64)[samples]
    xs = np.asarray(x, dtype=np.float64)[samples]
    n = zs.size
    fold = stretch_folds(np.zeros(n, dtype=np.int64) if segment is None
                         else np.asarray(segment)[samples])
    count = int(fold[-1]) + 1 if n else 0
    if count < 2:
        return 0.0
    groups = ordering.groups
    cell = fold * groups + ordering.group
    # Weight and moment of every (fold, group) in one pass.
    size = count * groups
    w_out = np.bincount(cell, weights=xs * xs, minlength=size).reshape(count, groups)
    m_out = np.bincount(cell, weights=xs * zs, minlength=size).reshape(count, groups)
    z_out = np.bincount(fold, weights=zs * zs, minlength=count)
    n_out = np.bincount(fold, minlength=count)
    weight, moment = w_out.sum(axis=0), m_out.sum(axis=0)
    total = float(np.sum(z_out))
    constants = np.zeros(count)
    estimates = np.zeros((count, groups))
    for f in range(count):
        train_w, train_m = weight - w_out[f], moment - m_out[f]
        train = GroupStats(train_w, train_m, total - float(z_out[f]), n - int(n_out[f]))
        constants[f] = float(np.sum(train_m) / np.sum(train_w))
        estimates[f] = (fit_banded(train, kind, nvr) if nvr > 0.0
                        else fit_flat(train, kind)).estimate
    constant_squares = float(np.sum((zs - xs * constants[fold]) ** 2))
    smoothed_squares = float(np.sum((zs - xs * estimates[fold, ordering.group]) ** 2))
    return constant_squares - smoothed_squares

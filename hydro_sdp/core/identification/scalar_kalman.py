"""The online identifier's six-state Kalman step on Python floats (docs/methods.md 7.2)."""

from __future__ import annotations

from hydro_sdp.core.arrays import FloatArray
import numpy as np

#: Positions of the diagonal ``P00, P11 .. P55`` in the packed upper triangle.
DIAGONAL = (0, 6, 11, 15, 18, 20)

Six = tuple[float, float, float, float, float, float]


def packed(matrix: FloatArray) -> list[float]:
    """
    Return the upper triangle of a 6 x 6 matrix, row by row, as Python floats.

    Returns: its 21 entries ``M[i, j]``, ``i <= j``.
    """
    rows, columns = np.triu_indices(6)
    return [float(value) for value in np.asarray(matrix, dtype=np.float64)[rows, columns]]


def unpacked(packed_matrix: list[float]) -> FloatArray:
    """Return the full symmetric 6 x 6 matrix of a packed upper triangle."""
    matrix = np.empty((6, 6))
    rows, columns = np.triu_indices(6)
    matrix[rows, columns] = packed_matrix
    matrix[columns, rows] = packed_matrix
    return matrix


def diagonal(packed_matrix: list[float]) -> FloatArray:
    """
    Return the diagonal of a packed matrix.

    ``packed_matrix``: the 21 entries of the upper triangle.
    """
    return np.array([packed_matrix[k] for k in DIAGONAL])


def add_to_diagonal(packed_matrix: list[float], values: Six) -> None:
    """
    Add six values to the diagonal of a packed matrix, in place.

    ``packed_matrix``: the 21 entries of the upper triangle; changed in place.
    """
    d0, d1, d2, d3, d4, d5 = values
    packed_matrix[0] += d0
    packed_matrix[6] += d1
    packed_matrix[11] += d2
    packed_matrix[15] += d3
    packed_matrix[18] += d4
    packed_matrix[20] += d5


def times(packed_matrix: list[float], x: Six) -> tuple[Six, float]:
    """
    Return ``M x`` and the quadratic form ``x' M x``.

    ``packed_matrix``: the 21 entries of the upper triangle of ``M``.
    Returns: ``M x`` (six floats, each summed from the first column to the last) and ``x' M x``,
    summed as ``x0 (M x)_0 + .. + x5 (M x)_5``.
    """
    (m00, m01, m02, m03, m04, m05, m11, m12, m13, m14, m15,
     m22, m23, m24, m25, m33, m34, m35, m44, m45, m55) = packed_matrix
    x0, x1, x2, x3, x4, x5 = x
    h0 = m00 * x0 + m01 * x1 + m02 * x2 + m03 * x3 + m04 * x4 + m05 * x5
    h1 = m01 * x0 + m11 * x1 + m12 * x2 + m13 * x3 + m14 * x4 + m15 * x5
    h2 = m02 * x0 + m12 * x1 + m22 * x2 + m23 * x3 + m24 * x4 + m25 * x5
    h3 = m03 * x0 + m13 * x1 + m23 * x2 + m33 * x3 + m34 * x4 + m35 * x5
    h4 = m04 * x0 + m14 * x1 + m24 * x2 + m34 * x3 + m44 * x4 + m45 * x5
    h5 = m05 * x0 + m15 * x1 + m25 * x2 + m35 * x3 + m45 * x4 + m55 * x5
    return (h0, h1, h2, h3, h4, h5), x0 * h0 + x1 * h1 + x2 * h2 + x3 * h3 + x4 * h4 + x5 * h5


def downdated(packed_matrix: list[float], gain: Six, h: Six) -> list[float]:
    """
    Return ``M - gain h'`` for a symmetric result (``gain`` a multiple of ``h``).

    ``packed_matrix``: the 21 entries of the upper triangle of ``M``.
    """
    (m00, m01, m02, m03, m04, m05, m11, m12, m13, m14, m15,
     m22, m23, m24, m25, m33, m34, m35, m44, m45, m55) = packed_matrix
    k0, k1, k2, k3, k4, k5 = gain
    h0, h1, h2, h3, h4, h5 = h
    return [m00 - k0 * h0, m01 - k0 * h1, m02 - k0 * h2, m03 - k0 * h3, m04 - k0 * h4,
            m05 - k0 * h5,
            m11 - k1 * h1, m12 - k1 * h2, m13 - k1 * h3, m14 - k1 * h4, m15 - k1 * h5,
            m22 - k2 * h2, m23 - k2 * h3, m24 - k2 * h4, m25 - k2 * h5,
            m33 - k3 * h3, m34 - k3 * h4, m35 - k3 * h5,
            m44 - k4 * h4, m45 - k4 * h5,
            m55 - k5 * h5]


def boxed(theta: list[float], gain: Six, innovation: float, lower: Six, upper: Six) -> list[float]:
    """
    Return ``theta + gain innovation`` projected on the box ``[lower, upper]``.

    Returns: the new coefficients (a new list); a NaN stays NaN, as through ``np.clip``.
    """
    a0, a1, a2, a3, a4, a5 = theta
    k0, k1, k2, k3, k4, k5 = gain
    a0 += k0 * innovation
    a1 += k1 * innovation
    a2 += k2 * innovation
    a3 += k3 * innovation
    a4 += k4 * innovation
    a5 += k5 * innovation
    l0, l1, l2, l3, l4, l5 = lower
    u0, u1, u2, u3, u4, u5 = upper
    return [l0 if a0 < l0 else u0 if a0 > u0 else a0,
            l1 if a1 < l1 else u1 if a1 > u1 else a1,
            l2 if a2 < l2 else u2 if a2 > u2 else a2,
            l3 if a3 < l3 else u3 if a3 > u3 else a3,
            l4 if a4 < l4 else u4 if a4 > u4 else a4,
            l5 if a5 < l5 else u5 if a5 > u5 else a5]

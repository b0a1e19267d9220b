"""
Structure identification by SRIV: every order and delay in a range, ranked (CAPTAIN ``rivid``).

The reasoning is in docs/methods.md sections 1.8, 1.9.

"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence
import warnings

from hydro_sdp.core.arrays import FloatArray
from hydro_sdp.core.errors import DataError, HydroSdpError
from hydro_sdp.core.identification.riv import NotConvergedWarning, sriv
import numpy as np


@dataclass(frozen=True)
class StructureRow:
    """
    One candidate structure of a search.

    Attributes
    ----------
    n : int
        Denominator order (known factor excluded).
    rt2 : float
        ``R_T^2``.
    rt2_diff : float
        ``R_T^2`` of the differenced output.

    """

    n: int
    m: int
    delay: int
    rt2: float
    rt2_diff: float
    yic: float
    converged: bool
    stable: bool


def structure_search(y: FloatArray | Sequence[FloatArray], u: FloatArray | Sequence[FloatArray],
                     n_range: Sequence[int], m_range: Sequence[int],
                     delay_range: Sequence[int], *, known_factor: Sequence[float] = (1.0,),
                     criterion: str = 'yic', min_rt2: float | None = None) -> list[StructureRow]:
    """
    Estimate every structure in a range and rank them (CAPTAIN ``rivid``, docs/methods.md 1.9).

    ``criterion``: ``yic`` (most negative first, among models with ``R_T^2 >= min_rt2``), ``rt2``
    or ``rt2_diff`` (largest first).
    ``min_rt2``: models below this ``R_T^2`` are ranked after all others for ``yic``; default:
    0.001 below the best ``R_T^2`` (methods 1.9).
    """
    if criterion not in ('yic', 'rt2', 'rt2_diff'):
        raise DataError(f'criterion must be yic, rt2 or rt2_diff, got {criterion!r}')
    rows = []
    for n in n_range:
        for m in m_range:
            for delay in delay_range:
                with warnings.catch_warnings(), np.errstate(all='ignore'):
                    warnings.simplefilter('ignore', NotConvergedWarning)
                    try:
                        estimate = sriv(y, u, n, m, delay, known_factor=known_factor)
                    except (HydroSdpError, np.linalg.LinAlgError):
                        continue
                stable = not any('not stable' in note for note in estimate.warnings)
                rows.append(StructureRow(n, m, delay, estimate.rt2, estimate.rt2_diff,
                                         estimate.yic, estimate.converged, stable))
    if min_rt2 is None:
        min_rt2 = max((row.rt2 for row in rows if row.stable and np.isfinite(row.rt2)),
                      default=0.0) - 1e-3
    if criterion == 'yic':
        def key(row: StructureRow) -> tuple[bool, float]:
            ok = row.rt2 >= min_rt2 and row.stable and np.isfinite(row.yic)
            return (not ok, row.yic if np.isfinite(row.yic) else np.inf)
    else:
        def key(row: StructureRow) -> tuple[bool, float]:
            value = getattr(row, criterion)
            return (not row.stable, -value if np.isfinite(value) else np.inf)
    return sorted(rows, key=key)

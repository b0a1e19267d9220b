"""The shape of ``load_dependence`` with a measured load (methods 8.2)."""

from __future__ import annotations

from typing import Sequence

from hydro_sdp.core.arrays import FloatArray
from hydro_sdp.core.diagnosis.naming import Naming
from hydro_sdp.core.identification.stroke_fit import hats, penalised_lstsq
import numpy as np

#: Knots of the factor.
KNOTS = 5
#: The factor is kept within these bounds (a load never stops or races the joint beyond).
FACTOR_RANGE = (0.05, 20.0)
#: Fewest samples a direction needs for its factor to be fitted (else 1).
MIN_SAMPLES = 50

#: The factor per direction at the knots: (positive, negative).
Table = tuple[FloatArray, FloatArray]


def load_knots(load: FloatArray) -> FloatArray:
    """
    Return knots over the loads seen: at the quantiles 0, 1/4, 1/2, 3/4 and 1.

    ``load``: loads of the samples where the model moves, load units.
    """
    knots = np.unique(np.quantile(load, np.linspace(0.0, 1.0, KNOTS)))
    if knots.size >= 2:
        # Knots closer than a thousandth of the range would make the basis degenerate.
        keep = np.r_[True, np.diff(knots) > 1e-3 * float(np.ptp(knots))]
        knots = knots[keep]
    return knots


def fitted_table(measured: FloatArray, predicted: FloatArray, load: FloatArray,
                 knots: FloatArray) -> Table:
    """
    Fit the factor's knot values per direction to the one-step increments.

    ``measured``, ``predicted``: measured and model increments, degrees.
    ``load``: load at each sample.
    Returns: the factors at the knots, positive and negative direction (1 where a direction has too
    few samples).
    """
    out = []
    for side in (predicted > 0.0, predicted < 0.0):
        if np.count_nonzero(side) < MIN_SAMPLES:
            out.append(np.ones(knots.size))
            continue
        design = hats(load[side], knots) * predicted[side][:, None]
        solution, _ = penalised_lstsq([design], [True], measured[side])
        out.append(np.clip(solution, *FACTOR_RANGE))
    return out[0], out[1]


def sdp_table(naming: Naming, knots: FloatArray) -> Table | None:
    """
    Read the factor at the knots off the SDP analysis's ratio along the load.

    Returns: the ratio's estimate per direction at the knots (1 for a direction not analysed); None
    when the load was not analysed.
    """
    found = [naming.ratio('load', direction) for direction in ('positive', 'negative')]
    if all(entry is None for entry in found):
        return None
    sides: Sequence[FloatArray] = [np.ones(knots.size) if entry is None else
                                   np.clip(entry.at(knots), *FACTOR_RANGE) for entry in found]
    return sides[0], sides[1]


def describe(knots: FloatArray, table: Table, unit: str = 'load units') -> str:
    """Return the factor in a few words: its value at the lowest and highest knot."""
    parts = [f'x{side[0]:.2f} at {knots[0]:.3g} to x{side[-1]:.2f} at {knots[-1]:.3g} {unit} '
             f'({name})' for side, name in zip(table, ('positive', 'negative'))]
    return ', '.join(parts)

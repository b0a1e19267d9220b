"""
West et al. (2018) eqs. (3)-(5) one sample at a time, as the paper writes them.

A plain Python loop over the six coefficients ``alpha_1..alpha_6`` (at the
sample period), the delay in samples and the end stops; it shares nothing with
:mod:`hydro_sdp.core.model.simulation`, which the tests check against it and the
foundation benchmark times against it.

"""

from __future__ import annotations

import math
from typing import Sequence

from hydro_sdp.core.arrays import FloatArray


def paper_recursion(alpha: Sequence[float], tau: int, v: FloatArray, y0: float,
                    y_min: float, y_max: float) -> list[float]:
    """
    Return the angles the paper's recursion gives for commands ``v``.

    Parameters
    ----------
    alpha : sequence of float
        ``(a1, a2, a3, a4, a5, a6)`` at the sample period.
    tau : int
        Delay, samples (commands before the first are 0).
    v : FloatArray
        Commands, one a sample.
    y0 : float
        Angle at the first sample, degrees (clamped to the stops).
    y_min, y_max : float
        End stops, degrees.

    Returns
    -------
    list of float
        Angles, one a sample.

    """
    a1, a2, a3, a4, a5, a6 = alpha
    y = [min(max(y0, y_min), y_max)]
    commands = v.tolist()
    for k in range(1, len(commands)):
        u = commands[k - tau] if k >= tau else 0.0
        if u < a3:
            q = a1 * (1.0 - math.exp(a2 * (u - a3)))
        elif u > a6:
            q = a4 * (1.0 - math.exp(-a5 * (u - a6)))
        else:
            q = 0.0
        y.append(min(max(y[-1] + q, y_min), y_max))
    return y

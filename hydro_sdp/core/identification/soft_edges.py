"""Eq. (5) and the gradient of its soft-edged form, on Python floats (docs/methods.md 7.2)."""

from __future__ import annotations

import math

from hydro_sdp.core.identification.scalar_kalman import Six


def map_and_soft_gradient(u: float, theta: list[float], kappa: float) -> tuple[float, Six]:
    """
    Return eq. (5) at ``u`` and the gradient of its soft-edged form.

    ``u``: the delayed command, input units.
    ``theta``: ``(a1 .. a6)`` of eq. (5) in per-sample form: ``(a1, a2, a3)`` below the dead-zone,
    ``(a4, a5, a6)`` above.
    ``kappa``: width of the soft edges, input units.
    Returns: the exact map ``q(u; theta)`` and ``d q_s / d theta`` of the soft-edged map.
    """
    a1, a2, a3, a4, a5, a6 = theta
    d_below = u - a3
    d_above = u - a6
    # min(d_below, 0) and max(d_above, 0), as the builtins return them.
    q = (a1 * -math.expm1(a2 * (0.0 if 0.0 < d_below else d_below)) +
         a4 * -math.expm1(-a5 * (0.0 if 0.0 > d_above else d_above)))
    # Smooth min(d_below, 0) = -softplus(-d_below) and max(d_above, 0) = softplus(d_above),
    # softplus(x) = kappa ln(1 + e^{x/kappa}), each branch free of overflow.
    z_below = d_below / kappa
    z_above = d_above / kappa
    below = -(kappa * (-z_below + math.log1p(math.exp(z_below))) if z_below < 0.0 else
              kappa * math.log1p(math.exp(-z_below)))
    above = (kappa * (z_above + math.log1p(math.exp(-z_above))) if z_above > 0.0 else
             kappa * math.log1p(math.exp(z_above)))
    e = math.exp(a2 * below)
    g = math.exp(-a5 * above)
    # The logistic slopes of the two softplus functions (exp capped against overflow).
    sigma_below = 1.0 / (1.0 + math.exp(700.0 if 700.0 < z_below else z_below))
    sigma_above = 1.0 / (1.0 + math.exp(700.0 if 700.0 < -z_above else -z_above))
    return q, (1.0 - e, -a1 * below * e, a1 * a2 * e * sigma_below,
               1.0 - g, a4 * above * g, -a4 * a5 * g * sigma_above)

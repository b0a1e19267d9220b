"""
The serial integration of a speed that depends on the angle just reached (methods 3.6).

The stroke factor is inlined: the arithmetic of ``StrokeGeometry.factor_at`` in the same order.
"""

from __future__ import annotations

from bisect import bisect_right
import math

from hydro_sdp.core.arrays import FloatArray
from hydro_sdp.core.model.effects import AngleDependentVelocity, StrokeGeometry
from hydro_sdp.core.model.timing import SamplePeriod
import numpy as np


def integrate_angle_dependent(speed: FloatArray, dt: SamplePeriod, y0: float, low: float,
                              high: float, gravity: AngleDependentVelocity | None,
                              geometry: StrokeGeometry | None) -> FloatArray:
    """
    Return the angles from ``y0`` under ``speed`` scaled by the angle effects, in the stops.

    ``speed``: speed per sample before the angle effects, deg/s (the first belongs to no interval).
    ``dt``: sample period, s.
    ``y0``: angle at the first sample, degrees (clamped into the stops).
    ``low``, ``high``: end stops, degrees.
    ``gravity``: the gravity-like effect, if the model has it.
    ``geometry``: the stroke factor, if the model has it.
    Returns: angle at each sample, degrees.
    """
    current = min(max(float(y0), low), high)
    # A list grows faster than a numpy array takes one float at a time.
    y = [current]
    append = y.append
    amplitude = gravity.amplitude if gravity is not None else 0.0
    phase = math.radians(gravity.phase) if gravity is not None else 0.0
    radians, cos = math.radians, math.cos
    if geometry is not None:
        knots, factors, asymmetry = geometry.knots, geometry.factors, geometry.asymmetry
        first, last, end = knots[0], knots[-1], len(knots) - 2
        cushion, cushion_factor = geometry.cushion, geometry.cushion_factor
        cushion_rest = 1.0 - cushion_factor
    for w in speed[1:].tolist():
        if geometry is not None:
            # StrokeGeometry.factor_at(current, w), operation for operation.
            if current <= first:
                index, weight = 0, 0.0
            elif current >= last:
                index, weight = end, 1.0
            else:
                index = bisect_right(knots, current) - 1
                weight = (current - knots[index]) / (knots[index + 1] - knots[index])
            factor = factors[index] + weight * (factors[index + 1] - factors[index])
            direction = 1.0 if w > 0.0 else -1.0 if w < 0.0 else 0.0
            if asymmetry:
                part = asymmetry[index] + weight * (asymmetry[index + 1] - asymmetry[index])
                factor *= 1.0 + direction * part
            if cushion > 0.0 and direction != 0.0:
                distance = last - current if direction > 0.0 else current - first
                share = distance / cushion
                share = 0.0 if share < 0.0 else 1.0 if share > 1.0 else share
                factor *= cushion_factor + cushion_rest * share
            w *= factor
        if gravity is not None:
            w += amplitude * abs(w) * cos(radians(current) + phase)
        # min(max(., low), high) without two calls per sample (the same float comes out).
        current += dt * w
        current = low if current < low else high if current > high else current
        append(current)
    return np.array(y, dtype=np.float64)

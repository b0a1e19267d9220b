"""
Stretches where a record stalls: driven beyond the dead-zone, not moving, not at a stop.

The reasoning is in docs/methods.md section 13.10.

"""

from __future__ import annotations

import math

from hydro_sdp.core.arrays import FloatArray
from hydro_sdp.core.model.exogenous_signals import Exogenous
from hydro_sdp.core.model.joint_model import JointModel
from hydro_sdp.core.model.records import Record
from hydro_sdp.core.model.simulation import speed_profile
from hydro_sdp.core.model.timing import SamplePeriod
import numpy as np

#: Window of the held test, s: the model moves the joint, the joint does not.
WINDOW = 0.3
#: Shortest stall reported, s.
MIN_STALL = 1.0
#: Nearest the far end of the travel a joint counts as at a stop, degrees (at least).
END_REACH = 1.0


def angle_noise(angles: FloatArray) -> float:
    """Robust angle noise from second differences (motion is mostly steady), degrees."""
    second = np.diff(angles, 2)
    return float(1.4826 * np.median(np.abs(second)) / math.sqrt(6.0)) if second.size else 0.0


def stalled(model: JointModel, record: Record, dt: SamplePeriod,
            travel: tuple[float, float] | None = None,
            exogenous: Exogenous | None = None) -> np.ndarray:
    """
    Mark the samples of a record where the joint stalls.

    ``dt``: its sample period, s.
    ``travel``: lowest and highest angle of all the records scored together (default: this one's).
    ``exogenous``: the record's load and other joints' speeds.
    Returns: one boolean per sample.
    """
    n = len(record)
    window = max(2, int(round(WINDOW / dt)))
    out = np.zeros(n, dtype=bool)
    if n <= window + 2:
        return out
    y = record.y
    speed = speed_profile(model, record.v, dt, v_before=float(record.v[0]), exogenous=exogenous)
    moved = np.cumsum(np.r_[0.0, dt * speed[1:]])
    driven = moved[window:] - moved[:-window]
    measured = y[window:] - y[:-window]
    noise = max(angle_noise(y), 1e-9)
    low, high = travel if travel is not None else (float(np.min(y)), float(np.max(y)))
    stops = model.angle_limits or (-math.inf, math.inf)
    reach = max(END_REACH, 10.0 * noise)
    start = y[:-window]
    at_end = ((driven > 0.0) & (start >= min(high, stops[1]) - reach)) | \
        ((driven < 0.0) & (start <= max(low, stops[0]) + reach))
    held = (np.abs(driven) > 10.0 * noise) & (np.abs(measured) < 0.2 * np.abs(driven)) & ~at_end
    # Runs of held windows, each window covering its samples; kept when long enough.
    edges = np.flatnonzero(np.diff(np.r_[0, held.astype(np.int8), 0]))
    for first, last in zip(edges[::2], edges[1::2]):
        if (last - first + window) * dt >= MIN_STALL:
            out[first:last + window] = True
    return out


def pieces_between(mask: np.ndarray, start: int, shortest: int = 2) -> list[tuple[int, int]]:
    """Return the ``[first, end)`` stretches from ``start`` on where ``mask`` is False."""
    free = ~mask.copy()
    free[:start] = False
    edges = np.flatnonzero(np.diff(np.r_[0, free.astype(np.int8), 0]))
    return [(int(a), int(b)) for a, b in zip(edges[::2], edges[1::2]) if b - a >= shortest]

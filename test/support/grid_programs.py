"""
Programs of the diagnosis grid: commands for a true joint, the other joint's levels, a load.

Random levels kept inside the end stops, or full strokes from stop to stop, planned on
the true joint's model file (its dead-zone, input limits and stops); see
:mod:`support.diagnosis_grid`.

"""

from __future__ import annotations

from hydro_sdp.core.arrays import FloatArray
from hydro_sdp.core.model.joint_model import JointModel
import numpy as np


def _level(rng: np.random.Generator, truth: JointModel, sign: float, smallest: float) -> float:
    """Return a command driving ``truth`` towards ``sign`` at a random share of its range."""
    assert truth.dead_zone is not None and truth.input_limits is not None
    side = 1 if sign > 0 else 0
    edge = truth.dead_zone[side]
    end = truth.input_limits[side]
    return edge + float(rng.uniform(smallest, 0.9)) * (end - edge)


def program(truth: JointModel, kind: str, rng: np.random.Generator, seconds: float,
            dt: float) -> tuple[FloatArray, float]:
    """
    Return commands for ``truth`` and the angle to start from.

    ``random``: random levels (dead-zone included) held 0.5-3 s, cut short before the
    joint would leave the middle 80 % of its stroke. ``stroke``: runs at a random level
    from one stop to the other, pushed against the stop for 0.3-1.5 s, some rests.

    Parameters
    ----------
    truth : JointModel
        The true joint's model (its stops and map plan the program).
    kind : str
        ``random`` or ``stroke``.
    rng : numpy.random.Generator
        Random draws.
    seconds : float
        Length, s.
    dt : float
        Sample period, s.

    Returns
    -------
    tuple[FloatArray, float]
        Commands and the start angle, degrees.

    """
    assert truth.angle_limits is not None
    low, high = truth.angle_limits
    rest = truth.rest_command
    total = int(round(seconds / dt))
    pieces: list[FloatArray] = []
    filled = 0
    y = 0.5 * (low + high)
    margin = 0.1 * (high - low)
    while filled < total:
        if kind == 'random':
            up = rng.random() < min(max((high - margin - y) / (high - low - 2 * margin),
                                        0.1), 0.9)
            sign = 1.0 if up else -1.0
            level = _level(rng, truth, sign, -0.3)
            if (level - rest) * sign < 0.0:
                level = rest
            speed = float(truth.rate(level))
            hold = float(rng.uniform(0.5, 3.0))
            if speed != 0.0:
                room = (high - margin - y) if speed > 0 else (y - low - margin)
                hold = min(hold, max(room, 0.0) / abs(speed))
            samples = max(1, int(round(hold / dt)))
            y += speed * samples * dt
            pieces.append(np.full(samples, level))
        else:
            sign = 1.0 if y < 0.5 * (low + high) else -1.0
            level = _level(rng, truth, sign, 0.3)
            speed = abs(float(truth.rate(level)))
            travel = (high - y) if sign > 0 else (y - low)
            hold = travel / max(speed, 1e-6) + float(rng.uniform(0.3, 1.5))
            pieces.append(np.full(int(round(hold / dt)), level))
            y = high if sign > 0 else low
            if rng.random() < 0.5:
                pieces.append(np.full(int(round(float(rng.uniform(0.3, 1.5)) / dt)), rest))
        filled = sum(p.size for p in pieces)
    return np.concatenate(pieces)[:total], 0.5 * (low + high)


def other_levels(rng: np.random.Generator, n: int, dt: float) -> FloatArray:
    """Return random levels of the other joint, moving half the time, within its stops."""
    out = np.zeros(n)
    k = 0
    sign = 1.0
    while k < n:
        samples = int(round(float(rng.uniform(0.5, 2.0)) / dt))
        out[k:k + samples] = sign * float(rng.uniform(2.0, 8.0)) if rng.random() < 0.5 else 0.0
        sign = -sign
        k += samples
    return out


def load_signal(rng: np.random.Generator, n: int, dt: float, payload: float) -> FloatArray:
    """Return a measured load: the record's payload and a digging force that comes and goes."""
    t = dt * np.arange(n)
    period = float(rng.uniform(6.0, 15.0))
    force = float(rng.uniform(10.0, 40.0)) * np.maximum(
        0.0, np.sin(2.0 * np.pi * t / period + float(rng.uniform(0.0, 6.3))))
    return payload + force

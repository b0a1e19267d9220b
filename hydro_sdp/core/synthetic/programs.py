"""
Open-loop input programs: steps (West et al. 2018 Fig. 1) and random levels (Fig. 4).

Command ranges come from the model; each level's sign keeps the joint inside its stops.
"""

from __future__ import annotations

import math

from hydro_sdp.core.arrays import FloatArray
from hydro_sdp.core.errors import ConfigurationError
from hydro_sdp.core.model.joint_model import JointModel
from hydro_sdp.core.model.static_maps import PolyMap, PwlMap, SdpMap
from hydro_sdp.core.model.timing import SamplePeriod
import numpy as np

# Fraction of the end-stop range a program may use around its centre.
_USABLE_RANGE = 0.8


def level_bounds(model: JointModel, *, saturation: float = 0.99
                 ) -> tuple[tuple[float, float], tuple[float, float]]:
    """
    Signed ``((small_neg, large_neg), (small_pos, large_pos))`` step commands per direction.

    Small ends lie 60 % of the way to the dead-zone's edge; large ends reach ``saturation``
    of an ``sdp`` map's speed, within 95 % of the input limits.

    ``saturation``: fraction of the saturation speed where an ``sdp`` map's span ends.
    Returns: the spans, negative then positive.
    """
    rest = model.rest_command
    static_map = model.static_map
    limits = model.input_limits
    spans = []
    for side, sign in ((0, -1.0), (1, 1.0)):
        if model.dead_zone is not None:
            edge = model.dead_zone[side]
            small = rest + 0.6 * (edge - rest)
            if isinstance(static_map, SdpMap):
                large = edge - sign * math.log(1.0 - saturation) / static_map.curvature[side]
            elif isinstance(static_map, PwlMap):
                large = static_map.knots[-1 if sign > 0 else 0]
            else:
                large = edge + sign * 3.0 * max(abs(edge - rest), 0.1 * _scale(limits))
        elif isinstance(static_map, PolyMap):
            small = rest + sign * 0.05 * abs(static_map.command_range[side])
            large = static_map.command_range[side]
        else:
            small = rest + sign * 0.05 * _scale(limits)
            large = rest + sign * 0.5 * _scale(limits)
        if limits is not None:
            bound = rest + 0.95 * (limits[side] - rest)
            large = max(large, bound) if sign < 0 else min(large, bound)
            small = max(small, bound) if sign < 0 else min(small, bound)
        spans.append((small, large))
    return spans[0], spans[1]


def _scale(limits: tuple[float, float] | None) -> float:
    return 1.0 if limits is None else max(abs(limits[0]), abs(limits[1]))


def _travel_band(model: JointModel, y0: float) -> tuple[float, float]:
    if model.angle_limits is None or not all(map(math.isfinite, model.angle_limits)):
        low, high = model.angle_limits or (-math.inf, math.inf)
        return max(y0 - 30.0, low), min(y0 + 30.0, high)
    low, high = model.angle_limits
    margin = 0.5 * (1.0 - _USABLE_RANGE) * (high - low)
    return low + margin, high - margin


def _rate(model: JointModel, v: float) -> float:
    return float(model.rate(np.array([v]))[0])


def step_program(model: JointModel, dt: float, *, steps: int = 40, hold: float = 2.0,
                 rest: float = 1.0, y0: float = 0.0) -> FloatArray:
    """
    Make steps from rest of increasing size, alternating in sign, separated by rests.

    ``model``: the joint, for the command range and to keep it inside its end stops.
    ``dt``: sample period, s.
    ``hold``: longest time a step is held, s (shortened before an end stop).
    ``rest``: rest before each step, s (also after the last one).
    ``y0``: angle at the start, degrees.
    Returns: command at each sample.
    """
    dt = SamplePeriod(dt)
    if steps < 2:
        raise ConfigurationError(f'a step program needs at least 2 steps, got {steps}')
    if not (hold > 0.0 and rest > 0.0):
        raise ConfigurationError(f'hold and rest must be > 0 s, got {hold} and {rest}')
    (small_neg, large_neg), (small_pos, large_pos) = level_bounds(model)
    per_side = (steps + 1) // 2
    magnitudes = np.linspace(0.0, 1.0, per_side)
    low, high = _travel_band(model, y0)
    base = model.rest_command
    y = float(y0)
    rest_samples = max(1, round(rest / dt))
    pieces = [np.full(rest_samples, base)]
    for k in range(steps):
        fraction = magnitudes[k // 2]
        positive = k % 2 == 0
        level = _level(positive, fraction, small_neg, large_neg, small_pos, large_pos)
        speed = _rate(model, level)
        if not low <= y + speed * hold <= high:
            positive = not positive
            level = _level(positive, fraction, small_neg, large_neg, small_pos, large_pos)
            speed = _rate(model, level)
        room = (high - y) if speed > 0 else (y - low)
        duration = hold if speed == 0.0 else min(hold, max(room, 0.0) / abs(speed))
        hold_samples = max(1, round(duration / dt))
        y += speed * hold_samples * dt
        pieces.append(np.full(hold_samples, level))
        pieces.append(np.full(rest_samples, base))
    return np.concatenate(pieces)


def _level(positive: bool, fraction: float, small_neg: float, large_neg: float,
           small_pos: float, large_pos: float) -> float:
    if positive:
        return small_pos + fraction * (large_pos - small_pos)
    return small_neg + fraction * (large_neg - small_neg)


def random_program(model: JointModel, dt: float, duration: float, *, seed: int = 0,
                   y0: float = 0.0, hold_range: tuple[float, float] = (0.5, 3.0)) -> FloatArray:
    """
    Make random command levels held for random times (evaluation runs).

    Sizes are uniform up to 90 % of saturation; signs pull the joint to mid-travel.

    ``dt``: sample period, s.
    ``duration``: length of the program, s.
    ``y0``: angle at the start, degrees.
    ``hold_range``: shortest and longest hold time, s.
    Returns: command at each sample.
    """
    dt = SamplePeriod(dt)
    if not duration > 0.0:
        raise ConfigurationError(f'duration must be > 0 s, got {duration}')
    rng = np.random.default_rng(seed)
    (small_neg, large_neg), (small_pos, large_pos) = level_bounds(model, saturation=0.9)
    base = model.rest_command
    low, high = _travel_band(model, y0)
    total = max(1, round(duration / dt))
    levels = np.empty(total)
    filled = 0
    y = float(y0)
    while filled < total:
        up_share = (high - y) / (high - low)
        positive = rng.random() < min(max(up_share, 0.1), 0.9)
        # Start from a little inside the dead-zone so that small commands are exercised too.
        fraction = rng.uniform(-0.5, 1.0)
        if positive:
            level = small_pos + fraction * (large_pos - small_pos)
        else:
            level = small_neg + fraction * (large_neg - small_neg)
        if (level - base) * (1.0 if positive else -1.0) < 0.0:
            level = base
        hold = rng.uniform(*hold_range)
        speed = _rate(model, level)
        if speed != 0.0:
            room = (high - y) if speed > 0 else (y - low)
            hold = min(hold, max(room, 0.0) / abs(speed))
        samples = min(max(1, round(hold / dt)), total - filled)
        levels[filled:filled + samples] = level
        filled += samples
        y += speed * samples * dt
    return levels


def start_angle(model: JointModel) -> float:
    """Angle (degrees) at which programs start by default: mid-travel, or 0 without end stops."""
    if model.angle_limits is None:
        return 0.0
    low, high = model.angle_limits
    if not (math.isfinite(low) and math.isfinite(high)):
        return min(max(0.0, low + 30.0 if math.isfinite(low) else 0.0),
                   high - 30.0 if math.isfinite(high) else math.inf)
    return 0.5 * (low + high)

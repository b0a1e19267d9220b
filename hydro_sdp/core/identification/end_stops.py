"""Where a joint is held by an end stop although its command drives it (methods 13.2)."""

from __future__ import annotations

from hydro_sdp.core.arrays import FloatArray
from hydro_sdp.core.model.timing import SamplePeriod
import numpy as np

#: Net speed, as a fraction of the moving speed, below which the joint counts as held.
HELD_FRACTION = 0.1
#: Net speed, as a fraction of the moving speed, the joint must have had just before.
MOVING_FRACTION = 0.3
#: Share of the windows after the stop that must stay held (bounces are tolerated).
STAYS = 0.8
#: Nearest a joint counts as sitting at a stop, degrees (at least; or six noise levels).
STOP_REACH = 0.25


def stop_window(dt: SamplePeriod) -> int:
    """Return the window of the net-displacement test, samples (about 0.3 s, at least 5)."""
    return max(5, int(round(0.3 / dt)))


def clamp_start(y: FloatArray, v: FloatArray, begin: int, end: int, *, delay: int,
                noise: float, window: int, limits: tuple[float, float] | None = None,
                extremes: tuple[float, float] | None = None,
                rest: float | None = None) -> tuple[int, float, int] | None:
    """
    First index in ``[begin, end)`` where the joint is held by an end stop, if any.

    ``y``, ``v``: angles (degrees) and commands of the whole record.
    ``delay``: largest delay, samples: the command must have been held that long before.
    ``noise``: angle noise standard deviation, degrees.
    ``limits``: known stops, degrees: a held joint counts only near the stop in the direction it
    moved.
    ``extremes``: lowest and highest angle of the whole record, degrees: without known stops, a
    stop lies at one of them (a stretch that reaches neither is not searched).
    ``rest``: rest command: a stop counts only when the held command drives the joint the way it
    moved (above rest up, below rest down).
    Returns: index where the joint arrives at the stop, the angle it is held at, and the stop's
    side (0 lower, 1 upper).
    """
    if end - begin < 2 * window + 2:
        return None
    segment = y[begin:end]
    if limits is None and extremes is not None:
        reach = max(0.05 * (extremes[1] - extremes[0]), 1.0)
        if np.max(segment) < extremes[1] - reach and np.min(segment) > extremes[0] + reach:
            return None
    net = (segment[window:] - segment[:-window]) / window
    speed = np.abs(net)
    moving_speed = float(np.percentile(speed, 90))
    floor = 4.0 * max(noise, 1e-9) / window
    if moving_speed <= 3.0 * floor:
        return None
    held = speed < max(HELD_FRACTION * moving_speed, floor)
    command = v[begin:end]
    # Only held samples that come within three windows of a fast one can be a stop: the
    # largest net speed of the three windows before each sample, all at once.
    padded = np.r_[np.zeros(3 * window), speed]
    recent = np.lib.stride_tricks.sliding_window_view(padded[:-1], 3 * window).max(axis=1)
    candidates = held & (recent >= MOVING_FRACTION * moving_speed)
    for index in np.flatnonzero(candidates[window:]) + window:
        earliest = max(int(index) - 3 * window, 0)
        before = net[earliest:index]
        fast = int(np.argmax(np.abs(before)))
        if abs(before[fast]) < MOVING_FRACTION * moving_speed:
            continue
        # The motion must come from the command that is now held: held since a delay
        # before the stop and since before the window where the joint moved, and
        # driving the way it moved (every map is increasing: positive commands move
        # the joint up).
        first = max(min(begin + index - window - delay, begin + earliest + fast), 0)
        if np.any(v[first:begin + index + 1] != v[begin + index]):
            continue
        if rest is not None and np.sign(v[begin + index] - rest) != np.sign(before[fast]):
            continue
        changed = np.flatnonzero(command[index:] != command[index])
        last = index + (int(changed[0]) if changed.size else command.size - index)
        stay = held[index:min(last, held.size)]
        if stay.size < window // 2 or np.mean(stay) < STAYS:
            continue
        direction = 1.0 if before[fast] > 0.0 else -1.0
        angle = float(np.median(segment[index:last]))
        if limits is not None:
            tolerance = max(0.05 * (limits[1] - limits[0]), 1.0)
            if (direction > 0 and angle < limits[1] - tolerance) or \
                    (direction < 0 and angle > limits[0] + tolerance):
                continue
        else:
            # A stop is at the far end of the travel: of the record's when known.
            low, high = extremes if extremes is not None else (float(np.min(segment)),
                                                               float(np.max(segment)))
            extreme = high if direction > 0 else low
            if abs(extreme - angle) > max(0.05 * (high - low), 1.0):
                continue
        # Arrival: the first sample, at most three windows back, within reach of the
        # held angle (the overshoot beyond it stays in the stretch that is cut out).
        reach = max(6.0 * noise, 0.02)
        back = max(int(index) - 3 * window, 0)
        arrived = np.flatnonzero(direction * (segment[back:index + 1] - angle) >= -reach)
        arrival = back + int(arrived[0]) if arrived.size else int(index)
        return begin + arrival, angle, int(direction > 0)
    return None


def driven_stop(level: float, rest: float,
                stops: tuple[float | None, float | None]) -> tuple[float, float] | None:
    """
    Return the stop a held command drives the joint towards, and the direction (+1 or -1).

    None when the command is the rest command (it drives nowhere) or that stop is unknown.
    """
    if not level != rest:
        return None
    side = int(level > rest)
    stop = stops[side]
    return None if stop is None else (stop, 1.0 if side else -1.0)


def pushes_into_stop(y: FloatArray, level: float, rest: float,
                     stops: tuple[float | None, float | None]) -> bool:
    """
    Whether a step starts at an end stop and its command drives into that stop.

    ``y``: angles of the step from its initial state on, degrees.
    ``rest``: rest command: above it the joint is driven up, below it down.
    ``stops``: lower and upper end stop (known or detected), degrees; None where unknown.
    """
    target = driven_stop(level, rest, stops)
    if y.size == 0 or target is None:
        return False
    stop, direction = target
    tolerance = stop_tolerance(stops)
    return bool(direction * (stop - y[0]) <= tolerance
                and np.all(direction * (y - stop) <= tolerance))


def stop_tolerance(stops: tuple[float | None, float | None]) -> float:
    """Return how near a stop a joint counts as at it, degrees (2 % of the travel, at least 1)."""
    low, high = stops
    travel = high - low if low is not None and high is not None else 0.0
    return max(0.02 * travel, 1.0)


def stop_reach(noise: float) -> float:
    """Return how near a stop a joint counts as sitting at it: :data:`STOP_REACH`, or 6 noise."""
    return max(STOP_REACH, 6.0 * noise)


def arrival_at_stop(y: FloatArray, level: float, rest: float,
                    stops: tuple[float | None, float | None], reach: float) -> int | None:
    """First sample at which a step reaches the stop its command drives it into, if it does."""
    target = driven_stop(level, rest, stops)
    if y.size < 2 or target is None:
        return None
    stop, direction = target
    at = np.flatnonzero(direction * (np.asarray(y[1:]) - stop) >= -reach)
    return int(at[0]) + 1 if at.size else None

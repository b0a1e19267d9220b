"""The link's increments at the stops, one sample at a time: the recursion of methods 3.6."""

from hydro_sdp.core.model.link_mode import LinkState
import numpy as np


def stepped_ringing_increments(mode, increment, previous, dt, before, low, high):
    """Return what ``simulation._ringing_increments`` returns, one sample at a time."""
    out = np.empty_like(increment)
    state = LinkState(mode, before)
    pressed = 0.0
    for k, (step, angle) in enumerate(zip(increment.tolist(), previous.tolist())):
        if pressed * step > 0.0:
            moved = 0.0
        else:
            # Leaving a stop it starts from the stop, whatever a sensor there reads.
            actuator = angle - state.e if not pressed else high if pressed > 0.0 else low
            moved, pressed = step, 0.0
            if step > 0.0 and actuator + step >= high:
                moved, pressed = max(high - actuator, 0.0), 1.0
            elif step < 0.0 and actuator + step <= low:
                moved, pressed = min(low - actuator, 0.0), -1.0
        e = state.e
        swung = state.step(moved / dt)
        stop = high if pressed > 0.0 else low
        if pressed and not low <= stop + e <= high:
            # The link swung beyond the stop, where the sensor cannot follow it.
            out[k] = min(max(stop + swung, low), high) - angle
        else:
            out[k] = moved + swung - e
    return out


def strokes_into_stops(seed, dt=0.01):
    """Return a record's actuator increments, noisy angles, a mode's settled speed and stops."""
    rng = np.random.default_rng(seed)
    n = int(rng.integers(10, 6000))
    levels = rng.choice([-30.0, -5.0, 0.0, 0.0, 5.0, 30.0],
                        size=max(1, n // int(rng.integers(20, 400)) + 1))
    increment = np.repeat(levels, int(np.ceil(n / levels.size)))[:n] * dt * rng.uniform(0.5, 1.5)
    low, high = -2.0, float(rng.uniform(5.0, 60.0))
    angles = np.clip(np.cumsum(increment) + rng.normal(0.0, 0.05, n), low, high)
    return increment, angles, float(increment[0] / dt), (low, high)

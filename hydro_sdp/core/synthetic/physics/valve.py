"""Spool valve: command to spool travel, spool dynamics and metering area (methods 11)."""

from __future__ import annotations

from bisect import bisect_right
import math

from hydro_sdp.core.arrays import FloatArray
from hydro_sdp.core.model.timing import delay_samples, delayed, DelayLine, SamplePeriod
from hydro_sdp.core.synthetic.physics.parameters import Valve
import numpy as np
from scipy.signal import lfilter

# mm^2 to m^2.
_MM2 = 1e-6


def spool_command(valve: Valve, commands: FloatArray) -> FloatArray:
    """Map commands (valve units) to the spool travel they ask for, fraction in [-1, 1]."""
    v = np.asarray(commands, dtype=np.float64)
    low, high = valve.limits
    above = (v - valve.neutral) / (high - valve.neutral)
    below = (v - valve.neutral) / (valve.neutral - low)
    return np.clip(np.where(v >= valve.neutral, above, below), -1.0, 1.0)


def lag_pole(valve: Valve, dt: SamplePeriod) -> float:
    """Pole of the spool's first-order lag at sample period ``dt`` (0 without lag)."""
    return math.exp(-dt / valve.time_constant) if valve.time_constant > 0.0 else 0.0


def spool_travel(valve: Valve, commands: FloatArray, dt: SamplePeriod, *,
                 command_before: float) -> FloatArray:
    """
    Spool travel over each sample interval: dead time, then a first-order lag.

    ``commands``: commands, one per sample, valve units.
    ``dt``: sample period, s.
    ``command_before``: command in force before the first sample (the spool starts settled on it).
    Returns: spool travel, fraction of full travel.
    """
    tau = delay_samples(valve.dead_time, dt) if valve.dead_time > 0.0 else 0
    before = float(spool_command(valve, np.array([command_before]))[0])
    u = delayed(spool_command(valve, commands), tau, before)
    p = lag_pole(valve, dt)
    if p == 0.0:
        return u
    x, _ = lfilter([1.0 - p], [1.0, -p], u, zi=[p * before])
    return np.asarray(x, dtype=np.float64)


class Spool:
    """
    The spool of :func:`spool_travel`, one sample at a time.

    ``dt``: sample period, s.
    """

    def __init__(self, valve: Valve, dt: SamplePeriod, command_before: float) -> None:
        self.valve = valve
        self._tau = delay_samples(valve.dead_time, dt) if valve.dead_time > 0.0 else 0
        self.travel = float(spool_command(valve, np.array([command_before]))[0])
        self._line = DelayLine(self._tau, self.travel)
        self._p = lag_pole(valve, dt)
        self._neutral = valve.neutral
        self._above = valve.limits[1] - valve.neutral
        self._below = valve.neutral - valve.limits[0]
        self.area = Notch(valve)

    def command(self, command: float) -> float:
        """Map one command to spool travel: :func:`spool_command`'s arithmetic, no arrays."""
        offset = command - self._neutral
        travel = offset / (self._above if command >= self._neutral else self._below)
        return min(max(travel, -1.0), 1.0)

    def step(self, command: float) -> float:
        """Take the command in force over the next interval; return the spool travel there."""
        self._line.push(self.command(command))
        u = self._line.delayed(self._tau)
        # Same arithmetic as lfilter's transposed direct form, so both paths agree.
        self.travel = u if self._p == 0.0 else (1.0 - self._p) * u + self._p * self.travel
        return self.travel


def metering_area(valve: Valve, travel: FloatArray) -> FloatArray:
    """Signed meter-in area ``Cd A(|x|)``, m^2, at spool ``travel`` (0 in the overlap)."""
    x = np.asarray(travel, dtype=np.float64)
    travels = np.array([valve.overlap] + [row[0] for row in valve.opening])
    areas = np.array([0.0] + [row[1] for row in valve.opening]) * _MM2
    magnitude = np.interp(np.abs(x), travels, areas, left=0.0)
    side = np.where(x < 0.0, -valve.retract_ratio, 1.0)
    return np.where(x == 0.0, 0.0, side) * valve.discharge_coefficient * magnitude


class Notch:
    """:func:`metering_area` of one valve at one travel at a time, (as :func:`numpy.interp`)."""

    def __init__(self, valve: Valve) -> None:
        self.travels = [valve.overlap] + [row[0] for row in valve.opening]
        self.areas = [0.0] + [row[1] * _MM2 for row in valve.opening]
        self.slopes = [(a1 - a0) / (t1 - t0) for t0, t1, a0, a1
                       in zip(self.travels, self.travels[1:], self.areas, self.areas[1:])]
        self.extend = 1.0 * valve.discharge_coefficient
        self.retract = -valve.retract_ratio * valve.discharge_coefficient

    def __call__(self, travel: float) -> float:
        """Signed effective area, m^2, at spool travel ``travel``."""
        x = abs(travel)
        j = bisect_right(self.travels, x) - 1
        if j < 0:
            magnitude = 0.0
        elif j == len(self.travels) - 1 or x == self.travels[j]:
            magnitude = self.areas[j]
        else:
            magnitude = self.slopes[j] * (x - self.travels[j]) + self.areas[j]
        side = 0.0 if travel == 0.0 else self.retract if travel < 0.0 else self.extend
        return side * magnitude

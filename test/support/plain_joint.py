"""
A hydraulic joint simulated from first principles for tests, independent of the package.

It imports nothing from ``hydro_sdp.core.model.simulation``, ``hydro_sdp.core.model.effects``
or the identification code: its own speed map (a dead-zone, a linear rise and
a saturation rounded by ``tanh``, written from the shape of West et al. 2018,
Fig. 3), its own dead time and first-order valve lag, its own integrator with
end stops, and optional speed factors of the angle and of a measured load
written here as plain functions. Stamps are written as a machine writes them:
seconds since 1970 with timer jitter.
"""

from __future__ import annotations

from dataclasses import dataclass
import math
from typing import Callable, Sequence

from hydro_sdp.core.model.records import Record
import numpy as np

#: Time since 1970 at which the generated records start, s.
EPOCH = 1.76e9


@dataclass(frozen=True)
class PlainJoint:
    """
    The joint: a speed map of the delayed command, a valve lag, an integrator.

    Parameters
    ----------
    dt : float
        Sample period, s.
    delay : int
        Dead time, samples.
    dead_zone : tuple[float, float]
        Commands between which the joint does not move.
    slope : tuple[float, float]
        Speed per command unit beyond each edge, deg/s per unit (negative, positive side).
    saturation : tuple[float, float]
        Largest speed on each side, deg/s.
    lag : float
        Valve time constant, s (0: none).
    stops : tuple[float, float]
        End stops, deg.
    noise : float
        Angle sensor noise, deg.
    angle_factor : callable or None
        ``f(angle, direction)``: speed factor along the stroke (direction +-1).
    load_factor : callable or None
        ``f(load, direction)``: speed factor of a measured load.

    """

    dt: float = 0.01
    delay: int = 12
    dead_zone: tuple[float, float] = (-0.9, 0.8)
    slope: tuple[float, float] = (14.0, 18.0)
    saturation: tuple[float, float] = (45.0, 55.0)
    lag: float = 0.0
    stops: tuple[float, float] = (-60.0, 70.0)
    noise: float = 0.02
    angle_factor: Callable[[float, float], float] | None = None
    load_factor: Callable[[float, float], float] | None = None

    def speed(self, v: float) -> float:
        """Steady speed at command ``v``, deg/s."""
        low, high = self.dead_zone
        if v > high:
            rise = self.slope[1] * (v - high)
            return self.saturation[1] * math.tanh(rise / self.saturation[1])
        if v < low:
            rise = self.slope[0] * (low - v)
            return -self.saturation[0] * math.tanh(rise / self.saturation[0])
        return 0.0

    def run(self, commands: Sequence[float], *, y0: float = 0.0,
            load: Sequence[float] | None = None, seed: int = 0,
            source: str = 'plain joint') -> Record:
        """
        Drive the joint with one command per sample and record it.

        Parameters
        ----------
        commands : sequence of float
            ``v_k``: the command in force over the interval ending at sample ``k``.
        y0 : float
            Angle at the first sample, deg.
        load : sequence of float or None
            Measured load per sample (kept in the record).
        seed : int
            Seed of the sensor noise and the timer jitter.
        source : str
            Name of the record.

        Returns
        -------
        Record
            The noisy record, stamped from ``EPOCH`` with jitter.

        """
        v = np.asarray(commands, dtype=float)
        n = v.size
        rng = np.random.default_rng(seed)
        pole = math.exp(-self.dt / self.lag) if self.lag > 0.0 else 0.0
        y = np.empty(n)
        y[0] = y0
        flow = 0.0
        for k in range(1, n):
            target = self.speed(float(v[max(k - self.delay, 0)]))
            flow = pole * flow + (1.0 - pole) * target
            speed = flow
            direction = 1.0 if speed > 0.0 else -1.0
            if self.angle_factor is not None and speed != 0.0:
                speed *= self.angle_factor(float(y[k - 1]), direction)
            if self.load_factor is not None and load is not None and speed != 0.0:
                speed *= self.load_factor(float(load[k - 1]), direction)
            y[k] = min(max(y[k - 1] + self.dt * speed, self.stops[0]), self.stops[1])
        t = EPOCH + self.dt * np.arange(1, n + 1) + rng.uniform(-0.05, 0.05, n) * self.dt
        measured = y + rng.normal(0.0, self.noise, n)
        return Record(t, v, measured, 'plain', source, origin=EPOCH,
                      load=None if load is None else np.asarray(load, dtype=float))


def steps(levels: Sequence[float], *, dt: float = 0.01, hold: float = 1.5,
          rest: float = 1.0) -> np.ndarray:
    """Commands of step experiments: rest, then each level held, rest again."""
    n_rest, n_hold = int(round(rest / dt)), int(round(hold / dt))
    parts = [np.zeros(n_rest)]
    for level in levels:
        parts += [np.full(n_hold, float(level)), np.zeros(n_rest)]
    return np.concatenate(parts)


def random_levels(duration: float, *, dt: float = 0.01, magnitude: tuple[float, float] = (
        1.0, 4.0), holds: tuple[float, float] = (0.5, 2.5), seed: int = 0) -> np.ndarray:
    """Random levels of either sign held for random times, with rests between some."""
    rng = np.random.default_rng(seed)
    parts = [np.zeros(int(round(0.5 / dt)))]
    total = int(round(duration / dt))
    while sum(p.size for p in parts) < total:
        level = rng.choice([-1.0, 1.0]) * rng.uniform(*magnitude)
        if rng.random() < 0.2:
            level = 0.0
        parts.append(np.full(int(round(rng.uniform(*holds) / dt)), level))
    return np.concatenate(parts)[:total]

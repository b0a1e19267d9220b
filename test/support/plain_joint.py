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
        drive = _Drive(self, y0)
        y = np.array([y0] + [drive.step(v, k, None if load is None else float(load[k - 1]))
                             for k in range(1, v.size)])
        return self._record(v, y, load, seed, source)

    def run_levels(self, duration: float, *, magnitude: tuple[float, float] = (1.0, 8.0),
                   holds: tuple[float, float] = (0.5, 2.5), y0: float = 0.0, margin: float = 10.0,
                   load: Callable[[float], float] | None = None, seed: int = 0,
                   source: str = 'random levels') -> Record:
        """
        Random levels held for random times, each heading away from the nearer stop.

        A level ends early within ``margin`` of the stop it heads for, as an operator lets go.

        Parameters
        ----------
        duration : float
            Length, s.
        magnitude : tuple[float, float]
            Range of the levels' size.
        holds : tuple[float, float]
            Range of the hold times, s.
        y0 : float
            Starting angle, deg.
        margin : float
            Distance from a stop at which a level ends, deg.
        load : callable or None
            Measured load as a function of time, s (kept in the record).
        seed : int
            Seed of the levels, the noise and the jitter.
        source : str
            Name of the record.

        Returns
        -------
        Record
            The run.

        """
        rng = np.random.default_rng([seed, 7])
        n = int(round(duration / self.dt))
        v = np.zeros(n)
        loads = None if load is None else np.array([load(k * self.dt) for k in range(n)])
        drive = _Drive(self, y0)
        y = [y0]
        k = 1
        while k < n:
            low, high = self.stops
            upward = rng.random() > (y[-1] - low) / (high - low)
            level = (1.0 if upward else -1.0) * rng.uniform(*magnitude)
            for _ in range(int(round(rng.uniform(*holds) / self.dt))):
                if k >= n or (upward and y[-1] > high - margin) or (
                        not upward and y[-1] < low + margin):
                    break
                v[k] = level
                y.append(drive.step(v, k, None if loads is None else float(loads[k - 1])))
                k += 1
        return self._record(v, np.array(y), loads, seed, source)

    def run_joystick(self, duration: float, *, reach: float = 4.0, period: float = 0.05,
                     hand: float = 0.15, moves: tuple[float, float] = (0.4, 1.6),
                     release: float = 0.2, neutral: float = 0.0, directions: str = 'both',
                     y0: float = 0.0, margin: float = 10.0, seed: int = 0,
                     source: str = 'operator') -> Record:
        """
        Drive the joint by an operator's joystick: a deflection chasing random targets.

        Each target is a deflection in ``(-1, 1)`` (0 with probability ``release``: the
        stick let go), chosen away from the nearer stop and held for a time drawn from
        ``moves``; the hand follows it with a first-order lag ``hand`` and lets go within
        ``margin`` of the stop it heads for. The command, sent every ``period`` on the
        joystick's bus, is the deflection times ``reach`` from ``neutral``, and
        ``neutral`` when the stick is let go.

        Parameters
        ----------
        duration : float
            Length, s.
        reach : float
            Command at full deflection.
        period : float
            Time between two commands on the bus, s.
        hand : float
            Time constant of the hand, s.
        moves : tuple[float, float]
            Range of the times a target is kept, s.
        release : float
            Probability that a target is the stick let go.
        neutral : float
            The valve's neutral command (0 for volts, 50 for a duty resting at 50 %).
        directions : str
            ``both``, or ``up`` for an operator who only ever pushes the stick one way.
        y0 : float
            Starting angle, deg.
        margin : float
            Distance from a stop at which the stick is let go, deg.
        seed : int
            Seed of the targets, the noise and the jitter.
        source : str
            Name of the record.

        Returns
        -------
        Record
            The run.

        """
        rng = np.random.default_rng([seed, 11])
        n = int(round(duration / self.dt))
        every = max(int(round(period / self.dt)), 1)
        follow = math.exp(-self.dt / hand)
        v = np.zeros(n)
        drive = _Drive(self, y0)
        y = [y0]
        v[0] = neutral
        deflection, target, until = 0.0, 0.0, 0
        for k in range(1, n):
            low, high = self.stops
            if k >= until:
                upward = directions == 'up' or rng.random() > (y[-1] - low) / (high - low)
                target = 0.0 if rng.random() < release else \
                    (1.0 if upward else -1.0) * rng.uniform(0.1, 1.0)
                until = k + int(round(rng.uniform(*moves) / self.dt))
            if (target > 0.0 and y[-1] > high - margin) or (target < 0.0 and y[-1] < low + margin):
                target = 0.0
            deflection = follow * deflection + (1.0 - follow) * target
            if k % every == 0:
                v[k] = neutral if target == 0.0 and abs(deflection) < 0.02 else \
                    neutral + reach * deflection
            else:
                v[k] = v[k - 1]
            y.append(drive.step(v, k, None))
        return self._record(v, np.array(y), None, seed, source)

    def _record(self, v: np.ndarray, y: np.ndarray, load: Sequence[float] | None, seed: int,
                source: str) -> Record:
        rng = np.random.default_rng(seed)
        n = v.size
        t = EPOCH + self.dt * np.arange(1, n + 1) + rng.uniform(-0.05, 0.05, n) * self.dt
        measured = y + rng.normal(0.0, self.noise, n)
        return Record(t, v, measured, 'plain', source, origin=EPOCH,
                      load=None if load is None else np.asarray(load, dtype=float))


class PlainPlant:
    """
    The joint stepped one sample at a time, a plant of ``support.independent_loop.run_loop``.

    ``angle`` is the noisy reading, ``true_angle`` the joint's angle; each ``step`` holds
    the command over one sample period.
    """

    def __init__(self, joint: PlainJoint, y0: float = 0.0, *, rest: float = 0.0,
                 seed: int = 0) -> None:
        self.joint = joint
        self.commands = [rest]
        self.drive = _Drive(joint, y0)
        self.rng = np.random.default_rng([seed, 13])
        self.true_angle = y0
        self.angle = y0 + float(self.rng.normal(0.0, joint.noise))

    def step(self, command: float) -> None:
        """Hold ``command`` over the next sample period."""
        self.commands.append(float(command))
        self.true_angle = self.drive.step(self.commands, len(self.commands) - 1, None)
        self.angle = self.true_angle + float(self.rng.normal(0.0, self.joint.noise))


class _Drive:
    """The joint's state while it is driven: the valve's flow and the angle."""

    def __init__(self, joint: PlainJoint, y0: float) -> None:
        self.joint = joint
        self.pole = math.exp(-joint.dt / joint.lag) if joint.lag > 0.0 else 0.0
        self.flow = 0.0
        self.y = y0

    def step(self, v: Sequence[float], k: int, load: float | None) -> float:
        """Advance over the interval ending at sample ``k``; return the angle there."""
        joint = self.joint
        target = joint.speed(float(v[max(k - joint.delay, 0)]))
        self.flow = self.pole * self.flow + (1.0 - self.pole) * target
        speed = self.flow
        direction = 1.0 if speed > 0.0 else -1.0
        if joint.angle_factor is not None and speed != 0.0:
            speed *= joint.angle_factor(self.y, direction)
        if joint.load_factor is not None and load is not None and speed != 0.0:
            speed *= joint.load_factor(load, direction)
        self.y = min(max(self.y + joint.dt * speed, joint.stops[0]), joint.stops[1])
        return self.y


def steps(levels: Sequence[float], *, dt: float = 0.01, hold: float = 1.5,
          rest: float = 1.0) -> np.ndarray:
    """Commands of step experiments: rest, then each level held, rest again."""
    n_rest, n_hold = int(round(rest / dt)), int(round(hold / dt))
    parts = [np.zeros(n_rest)]
    for level in levels:
        parts += [np.full(n_hold, float(level)), np.zeros(n_rest)]
    return np.concatenate(parts)

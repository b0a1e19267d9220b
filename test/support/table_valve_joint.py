"""
A hydraulic joint whose speed map is a measured table, simulated without hydro_sdp's model.

The joint is what a spool valve on a cylinder looks like from its command: the
command reaches the spool after a pure dead time and a first-order lag (the
pilot stage), the spool position sets the joint speed through a table of
measured speeds (a convex rise from a wide dead-zone that saturates: the
metering notch opens progressively, then the pump's flow is all there is),
and the joint integrates the speed between end stops; the angle sensor adds
white noise. The lag acts on the spool, before the table (as in a valve), not
on the speed as in hydro_sdp's ``valve_lag``, and the table is interpolated by
a monotone cubic (PCHIP), which is none of hydro_sdp's map families.

The default table is an excavator arm driven by a signed percent duty, as
logged on a real machine: nothing moves within about +-36 % duty, the speed
rises convexly to about 30 deg/s extending (27 deg/s retracting, the annulus
side) by 70-80 % and stays there; dead time 0.28 s, spool lag 0.15 s. Other
valve interfaces are the same joint seen through a linear change of unit
(:attr:`TableJoint.rest` and :attr:`TableJoint.units_per_percent`): percent
duty resting at 50 is ``rest=50, units_per_percent=0.5``.

Nothing here imports from ``hydro_sdp``.

"""

from __future__ import annotations

import csv
from dataclasses import dataclass
from functools import cached_property
import math
from pathlib import Path
from typing import Sequence

import numpy as np
from scipy.interpolate import PchipInterpolator

#: Signed duty (percent) and measured joint speed (deg/s) of the arm-like joint.
ARM_DUTY = (-100.0, -90.0, -80.0, -70.0, -60.0, -50.0, -40.0, -37.0,
            36.0, 40.0, 50.0, 60.0, 70.0, 80.0, 90.0, 100.0)
ARM_SPEED = (-27.5, -27.2, -26.0, -19.0, -10.5, -3.6, -0.9, 0.0,
             0.0, 1.0, 4.0, 12.6, 19.8, 29.0, 30.6, 30.9)


@dataclass(frozen=True)
class TableJoint:
    """
    One joint: a measured speed table behind a dead time and a spool lag.

    Parameters
    ----------
    duty : tuple[float, ...]
        Signed duty of the table, percent, increasing; zero speed in between
        the two innermost points around 0.
    speed : tuple[float, ...]
        Joint speed at each duty, deg/s, non-decreasing.
    dead_time : float
        Command to spool, s.
    lag : float
        Spool time constant, s.
    stroke : tuple[float, float]
        End stops, degrees.
    rest : float
        Command (valve units) of zero duty.
    units_per_percent : float
        Valve units per percent of duty.
    noise : float
        Angle sensor noise, standard deviation, degrees.

    """

    duty: tuple[float, ...] = ARM_DUTY
    speed: tuple[float, ...] = ARM_SPEED
    dead_time: float = 0.28
    lag: float = 0.15
    stroke: tuple[float, float] = (-45.0, 40.0)
    rest: float = 0.0
    units_per_percent: float = 1.0
    noise: float = 0.01

    @property
    def command_limits(self) -> tuple[float, float]:
        """Commands of -100 % and +100 % duty, valve units (increasing)."""
        ends = sorted(self.command(np.array([-100.0, 100.0])).tolist())
        return ends[0], ends[1]

    def command(self, duty: np.ndarray | float) -> np.ndarray:
        """Valve command of a signed duty (percent)."""
        return self.rest + self.units_per_percent * np.asarray(duty, dtype=float)

    def to_duty(self, command: np.ndarray | float) -> np.ndarray:
        """Signed duty (percent) of a valve command, clipped to +-100 %."""
        duty = (np.asarray(command, dtype=float) - self.rest) / self.units_per_percent
        return np.clip(duty, -100.0, 100.0)

    @cached_property
    def _table(self) -> PchipInterpolator:
        return PchipInterpolator(np.asarray(self.duty), np.asarray(self.speed))

    @cached_property
    def closed(self) -> tuple[float, float]:
        """Duty range of zero speed (between the table's zero points), percent."""
        zero = [d for d, s in zip(self.duty, self.speed) if s == 0.0]
        return min(zero), max(zero)

    def speed_at(self, duty: np.ndarray | float) -> np.ndarray:
        """Joint speed, deg/s, at a steady spool position given as signed duty."""
        inner = np.clip(np.asarray(duty, dtype=float), self.duty[0], self.duty[-1])
        closed = (inner > self.closed[0]) & (inner < self.closed[1])
        return np.where(closed, 0.0, self._table(inner))


class TableJointSimulator:
    """
    Step the joint one sample at a time: the command given is in force over the next sample.

    Parameters
    ----------
    joint : TableJoint
        The joint.
    dt : float
        Sample period, s.
    y0 : float
        Starting angle, degrees.
    command_before : float
        Command in force before the start (the spool has settled on it).
    seed : int
        Seed of the sensor noise.

    """

    def __init__(self, joint: TableJoint, dt: float, y0: float, *,
                 command_before: float | None = None, seed: int = 0) -> None:
        self.joint = joint
        self.dt = dt
        before = joint.rest if command_before is None else command_before
        self._queue = [float(joint.to_duty(before))] * max(1, int(round(joint.dead_time / dt)))
        self._pole = math.exp(-dt / joint.lag) if joint.lag > 0.0 else 0.0
        self._spool = self._queue[0]
        self._angle = min(max(float(y0), joint.stroke[0]), joint.stroke[1])
        self._rng = np.random.default_rng(seed)
        self.angle = self._measure()

    @property
    def true_angle(self) -> float:
        """Return the joint's angle without the sensor noise, degrees."""
        return self._angle

    def _measure(self) -> float:
        return self._angle + (self._rng.normal(0.0, self.joint.noise) if self.joint.noise else 0.0)

    def step(self, command: float) -> float:
        """Apply ``command`` over the next sample; return the angle the sensor reads then."""
        self._queue.append(float(self.joint.to_duty(command)))
        arrived = self._queue.pop(0)
        self._spool = self._pole * self._spool + (1.0 - self._pole) * arrived
        speed = float(self.joint.speed_at(self._spool))
        low, high = self.joint.stroke
        self._angle = min(max(self._angle + self.dt * speed, low), high)
        self.angle = self._measure()
        return self.angle


def run_commands(joint: TableJoint, commands: Sequence[float], dt: float, y0: float, *,
                 seed: int = 0) -> np.ndarray:
    """
    Angles read at each sample for commands in force over the interval ending there.

    ``angles[0]`` is read before ``commands[1]`` acts; ``commands[0]`` is the
    command in force before the run.
    """
    sim = TableJointSimulator(joint, dt, y0, command_before=commands[0], seed=seed)
    angles = [sim.angle]
    for command in commands[1:]:
        angles.append(sim.step(float(command)))
    return np.asarray(angles)


def stroke_run(joint: TableJoint, duty: float, dt: float, *, rest: float = 1.0,
               on_stop: float = 1.0, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """
    Log one duty driven from stop to stop and back, as a logger writes it.

    The joint rests at the lower stop, extends at ``duty`` until it meets the
    upper stop and ``on_stop`` s beyond, rests, retracts at ``-duty`` to the
    lower stop and ``on_stop`` s beyond, and rests again.

    Returns
    -------
    tuple of numpy arrays
        ``(commands, angles)``: the command applied at each row (valve units;
        it acts from that row on) and the angle read at that row.

    """
    low, high = joint.stroke
    sim = TableJointSimulator(joint, dt, low, seed=seed)
    commands: list[float] = []
    angles: list[float] = []

    def hold(command: float, seconds: float | None, stop: float | None = None) -> None:
        limit = 600.0 if seconds is None else seconds
        beyond = None
        for _ in range(int(round(limit / dt))):
            commands.append(command)
            angles.append(sim.angle)
            sim.step(command)
            if stop is not None and beyond is None and abs(sim.true_angle - stop) < 1e-9:
                beyond = int(round(on_stop / dt))
            if beyond is not None:
                beyond -= 1
                if beyond <= 0:
                    return

    idle = float(joint.command(0.0))
    hold(idle, rest)
    hold(float(joint.command(abs(duty))), None, high)
    hold(idle, rest)
    hold(float(joint.command(-abs(duty))), None, low)
    hold(idle, rest)
    return np.asarray(commands), np.asarray(angles)


def write_log(path: Path, commands: np.ndarray, angles: np.ndarray, dt: float, *,
              start: float = 0.0) -> Path:
    """Write a CSV log with columns ``t, arm_deg, duty``."""
    with open(path, 'w', newline='') as stream:
        writer = csv.writer(stream)
        writer.writerow(['t', 'arm_deg', 'duty'])
        for k, (command, angle) in enumerate(zip(commands, angles)):
            writer.writerow([f'{start + k * dt:.4f}', f'{angle:.5f}', f'{command:.4f}'])
    return path

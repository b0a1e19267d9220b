"""
A PIP-IDZ loop written from the equations, reading the controller file itself.

It uses none of hydro_sdp's controller classes: the file is read with PyYAML,
the control law is the incremental PIP of docs/methods.md section 4.2 (for
``n = 1, m = 3`` eq. (8) of West et al. 2018), ``u`` is clamped to
``u_limits``, the inverse dead-zone is the chord of section 5.1 or the table
of section 5.4 (zero band, with or without its fade-in band, or hysteresis),
the command is clamped to ``v_limits`` and the history keeps the increment the
valve really gives. The plant is any object with ``angle`` (the reading now)
and ``step(command)``, stepped at its own period with the command held between
control instants. :func:`judge` counts the valve's pulses at hold from the
definition of section 5.7, written again here.

"""

from __future__ import annotations

from dataclasses import dataclass
import math
from pathlib import Path
from typing import Sequence

import numpy as np
import yaml


@dataclass
class FileController:
    """The controller of a controller file, stepped once per control period."""

    f: list[float]
    g: list[float]
    k_i: float
    period: float
    idz: dict
    u_limits: tuple[float, float] | None
    v_limits: tuple[float, float] | None

    @classmethod
    def read(cls, path: str | Path) -> FileController:
        data = yaml.safe_load(Path(path).read_text())
        limits = [None if data.get(key) is None else tuple(data[key])
                  for key in ('u_limits', 'v_limits')]
        return cls(list(data['f']), list(data['g']), float(data['kI']),
                   float(data['control_period']), dict(data['idz']), limits[0], limits[1])

    def __post_init__(self) -> None:
        self.ys: list[float] = []
        self.us = [0.0] * (len(self.g) + 1)
        self.branch = 0
        self.rest = float(self.idz.get('rest', 0.0))
        self.beta = float(self.idz.get('beta', 0.05))
        self.mode = self.idz.get('mode', 'zero')
        self.fade = float(self.idz.get('fade', 0.0))
        if self.mode not in ('zero', 'hysteresis'):
            raise ValueError(f'mode {self.mode} is not written here')
        if 'table' in self.idz:
            u = np.asarray(self.idz['table']['u'], dtype=float)
            v = np.asarray(self.idz['table']['v'], dtype=float)
            zeros = np.flatnonzero(u == 0.0)
            self.negative = (u[:zeros[0] + 1], v[:zeros[0] + 1])
            self.positive = (u[zeros[-1]:], v[zeros[-1]:])
            self.table = (u, v)
            self.edges = (float(v[zeros[0]]), float(v[zeros[-1]]))
        else:
            self.table = None
            self.edges = tuple(self.idz['dead_zone'])
            self.slopes = tuple(self.idz['slopes'])

    def _branch_command(self, u: float, side: int) -> float:
        low, high = self.edges
        if self.table is None:
            if side > 0:
                return max(u / self.slopes[1] + high, low)
            return min(u / self.slopes[0] + low, high)
        us, vs = self.positive if side > 0 else self.negative
        if side > 0 and u < 0.0:
            return max(vs[0] + u * (vs[1] - vs[0]) / (us[1] - us[0]), low)
        if side < 0 and u > 0.0:
            return min(vs[-1] + u * (vs[-1] - vs[-2]) / (us[-1] - us[-2]), high)
        return float(np.interp(u, us, vs))

    def _valve(self, u: float, branch: int) -> float:
        """Return the command of ``u`` on ``branch`` (0: rest), the fade-in band applied."""
        if branch == 0:
            return self.rest
        v = self._branch_command(u, branch)
        if self.fade > 0.0 and self.mode == 'zero':
            # Beyond the band the command leaves rest as tanh((|u| - beta) / fade).
            v = self.rest + math.tanh((abs(u) - self.beta) / self.fade) * (v - self.rest)
        return v

    def _increment(self, v: float) -> float:
        if self.table is not None:
            return float(np.interp(v, *self.table[::-1]))
        low, high = self.edges
        if v < low:
            return self.slopes[0] * (v - low)
        return self.slopes[1] * (v - high) if v > high else 0.0

    def _table_slopes(self) -> tuple[float, float]:
        """Each branch's chord from its edge to two thirds of its largest increment."""
        slopes = []
        for (us, vs), edge, end in ((self.negative, self.edges[0], 0),
                                    (self.positive, self.edges[1], -1)):
            target = 2.0 / 3.0 * us[end]
            order = np.argsort(us)
            slopes.append(target / (float(np.interp(target, us[order], vs[order])) - edge))
        return slopes[0], slopes[1]

    def recalibrate(self, edges: tuple[float, float], slopes: tuple[float, float]) -> None:
        """
        Take new IDZ edges and slopes as the controller node does (methods.md 5.4).

        A chord takes them as they are; a table scales each branch's increments by
        new over old slope and shifts its commands by the edge's change. The stored
        increments are those the new IDZ gives for the commands of the old one, so
        the valve does not jump.
        """
        commands = [self._valve(u, self.branch) if self.branch else None for u in self.us]
        if self.table is None:
            self.edges, self.slopes = tuple(edges), tuple(slopes)
        else:
            ratios = [new / now for new, now in zip(slopes, self._table_slopes())]
            shifts = [new - now for new, now in zip(edges, self.edges)]
            (nu, nv), (pu, pv) = self.negative, self.positive
            self.negative = (nu * ratios[0], nv + shifts[0])
            self.positive = (pu * ratios[1], pv + shifts[1])
            if self.negative[1][-1] == self.positive[1][0]:
                u = np.r_[self.negative[0], self.positive[0][1:]]
                v = np.r_[self.negative[1], self.positive[1][1:]]
            else:
                u = np.r_[self.negative[0], self.positive[0]]
                v = np.r_[self.negative[1], self.positive[1]]
            self.table = (u, v)
            self.edges = (float(self.negative[1][-1]), float(self.positive[1][0]))
        self.us = [u if v is None else self._increment(v) for u, v in zip(self.us, commands)]

    def step(self, setpoint: float, y: float) -> float:
        """One control sample: the valve command for the angle ``y``."""
        n = len(self.f)
        ys = [y] + (self.ys[:n] if self.ys else [y] * n)
        us = self.us
        u = us[0] + self.k_i * (setpoint - y)
        for j, g_j in enumerate(self.g, start=1):
            u -= g_j * (us[j - 1] - us[j])
        for i, f_i in enumerate(self.f):
            u -= f_i * (ys[i] - ys[i + 1])
        if self.u_limits is not None:
            u = min(max(u, self.u_limits[0]), self.u_limits[1])
        if self.table is not None:
            u = min(max(u, float(self.table[0][0])), float(self.table[0][-1]))
        if u > self.beta:
            self.branch = 1
        elif u < -self.beta:
            self.branch = -1
        elif self.mode == 'zero':
            self.branch = 0
        v = self._valve(u, self.branch)
        if self.v_limits is not None and not self.v_limits[0] <= v <= self.v_limits[1]:
            v = min(max(v, self.v_limits[0]), self.v_limits[1])
            u = self._increment(v)
        self.ys = ys[:n + 1]
        self.us = [u] + us[:len(self.g)]
        return v


@dataclass
class LoopRun:
    """True angles, readings, set-points and commands at every plant sample."""

    t: np.ndarray
    y: np.ndarray
    measured: np.ndarray
    setpoint: np.ndarray
    v: np.ndarray


def run_loop(controller: FileController, plant, dt: float, levels: Sequence[float],
             hold: float) -> LoopRun:
    """
    Hold each set-point ``hold`` s; the controller acts every control period.

    ``plant.angle`` is what the controller reads; ``plant.true_angle`` (when the
    plant has it) the angle judged, without the sensor noise.
    """
    every = int(round(controller.period / dt))
    setpoint = np.repeat(np.asarray(levels, dtype=float), int(round(hold / dt)))
    y, measured, v = (np.empty(setpoint.size) for _ in range(3))
    command = controller.rest
    for j in range(setpoint.size):
        measured[j] = plant.angle
        y[j] = getattr(plant, 'true_angle', measured[j])
        if j % every == 0:
            command = controller.step(float(setpoint[j]), measured[j])
        v[j] = command
        plant.step(command)
    return LoopRun(np.arange(setpoint.size) * dt, y, measured, setpoint, v)


@dataclass
class StepResult:
    """Settling, overshoot, the end of one hold and the valve's work while it held."""

    size: float
    settling: float
    overshoot: float
    reversals: int
    wander: float
    pulses: int = 0
    travel: float = 0.0
    held: float = 0.0


def openings(v: np.ndarray, edges: tuple[float, float], rest: float) -> int:
    """
    Count the valve's openings across its dead-zone (methods.md section 5.7).

    The valve is shut within the inner half of the dead-zone around ``rest`` and
    open beyond an edge; in between it is where it was. An opening is the valve
    coming to one side from shut or from the other side.
    """
    low, high = edges
    last, count = None, 0
    for command in v:
        if command < low:
            side = -1
        elif command > high:
            side = 1
        elif rest - (rest - low) / 2 <= command <= rest + (high - rest) / 2:
            side = 0
        else:
            continue
        if side != 0 and last is not None and side != last:
            count += 1
        last = side
    return count


def judge(run: LoopRun, *, band: float = 0.5, tail: float = 2.0,
          rest: float = 0.0, edges: tuple[float, float] | None = None) -> list[StepResult]:
    """
    Settling into ``band``, overshoot (% of the step) and the last ``tail`` s of each hold.

    ``reversals`` counts sign changes of the command about ``rest`` in the tail
    (samples at rest ignored), ``wander`` the angle's range there. With the
    valve's dead-zone ``edges``, ``pulses`` counts its openings from the
    settling to the end of the hold (``held`` s) and ``travel`` the sum of the
    command's changes there.
    """
    dt = float(run.t[1] - run.t[0])
    y = run.y
    changes = np.r_[0, np.flatnonzero(np.diff(run.setpoint)) + 1, run.setpoint.size]
    results = []
    for start, end in zip(changes[:-1], changes[1:]):
        if start == 0:
            continue
        target, before = run.setpoint[start], run.setpoint[start - 1]
        error = y[start:end] - target
        outside = np.flatnonzero(np.abs(error) > band)
        settling = 0.0 if not outside.size else (
            math.inf if outside[-1] == error.size - 1 else (outside[-1] + 1) * dt)
        size = target - before
        overshoot = max(0.0, 100.0 * float(np.max(np.sign(size) * error)) / abs(size))
        window = slice(end - int(round(tail / dt)), end)
        side = np.sign(run.v[window] - rest)
        side = side[side != 0]
        reversals = int(np.count_nonzero(np.diff(side)))
        settled = start + (int(outside[-1]) + 1 if outside.size else 0)
        held = run.v[settled:end]
        results.append(StepResult(
            float(size), settling, overshoot, reversals, float(np.ptp(y[window])),
            0 if edges is None or held.size < 2 else openings(held, edges, rest),
            float(np.sum(np.abs(np.diff(held)))) if held.size > 1 else 0.0,
            (end - settled) * dt))
    return results

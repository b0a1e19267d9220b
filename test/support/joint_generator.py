"""
Hydraulic joints simulated for tests from the physics and the model file's documentation.

Independent of the package: nothing here comes from ``hydro_sdp.core.model.simulation``,
``hydro_sdp.core.model.effects`` or the diagnosis; only the
:class:`~hydro_sdp.core.model.records.Record` it returns is the package's. Every part is
written again from the physics or from the model file's documentation
(docs/interfaces.md section 1.3, docs/methods.md sections 3.1 and 3.6):

* the speed of a steady command: eq. (5) of West et al. (``exp``), straight lines
  beyond the dead-zone edges (``linear``), a ``tanh`` rise or a measured ``table``
  (monotone cubic between its points);
* a dead time per direction of motion, a first-order lag of the speed (the model file's
  ``valve_lag``) or of the spool before the map (a pilot stage);
* end stops, play between actuator and sensor (``backlash``), a speed factor of the
  angle that mirrors between the directions (gravity-like) or is shared by them (the
  linkage, with end cushions), a factor of a measured load, and one pump shared with the
  machine's other joints as the model file documents ``flow_sharing``: the joint's own
  demand and the others' speeds over what counts as a full demand, the pump's share of
  their sum (the physics plant shares its pump by the flows the valves ask for);
* the link ringing on the oil column behind the actuator (``oscillation``): a mass on a
  spring driven by the actuator's angle, ``y'' = w^2 (x - y) - 2 d w y'``, integrated by
  Runge-Kutta over each sub-step with the actuator moving at that sub-step's speed;
* its own integrator: every sample cut into sub-steps; the lag integrated exactly
  over each, the angle factors taken at the sub-step's mid-angle, the stops, the
  play and the pump's share applied at every sub-step (the others' speeds those of the
  sub-step before).

Stamps are written as a machine writes them: seconds since 1970, with timer jitter.

"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property
import math
from typing import Callable, Sequence

from hydro_sdp.core.model.records import Record
import numpy as np
from scipy.interpolate import PchipInterpolator

#: Time since 1970 at which generated records start, s.
EPOCH = 1.76e9
#: Sub-steps per sample of the integrator.
SUBSTEPS = 4


@dataclass(frozen=True)
class SpeedMap:
    """
    Steady joint speed (deg/s) of a command.

    Parameters
    ----------
    kind : str
        ``exp``: ``size (1 - exp(-rise u))`` beyond each edge, ``u`` the distance from
        it (West et al. eq. (5)); ``linear``: ``rise u``; ``tanh``: ``size tanh(rise u /
        size)``; ``table``: a monotone cubic through ``points``.
    dead_zone : tuple[float, float]
        Edges, command units: no motion in between.
    size : tuple[float, float]
        Largest speed below and above, deg/s (magnitudes; ``exp`` and ``tanh``).
    rise : tuple[float, float]
        Curvature (``exp``, 1/unit) or slope (``linear``, ``tanh``: deg/s per unit).
    points : tuple[tuple[float, float], ...]
        ``table``: (command, speed) pairs, commands increasing, speeds non-decreasing,
        zero at the dead-zone edges.

    """

    kind: str
    dead_zone: tuple[float, float]
    size: tuple[float, float] = (1.0, 1.0)
    rise: tuple[float, float] = (1.0, 1.0)
    points: tuple[tuple[float, float], ...] = ()

    def speed(self, v: float) -> float:
        """Return the steady speed at command ``v``, deg/s."""
        low, high = self.dead_zone
        if low <= v <= high:
            return 0.0
        side = 1 if v > high else 0
        u = v - high if side else low - v
        sign = 1.0 if side else -1.0
        if self.kind == 'exp':
            return sign * self.size[side] * -math.expm1(-self.rise[side] * u)
        if self.kind == 'linear':
            return sign * self.rise[side] * u
        if self.kind == 'tanh':
            return sign * self.size[side] * math.tanh(self.rise[side] * u / self.size[side])
        return float(self._table(min(max(v, self.points[0][0]), self.points[-1][0])))

    @cached_property
    def _table(self) -> PchipInterpolator:
        commands, speeds = zip(*self.points)
        return PchipInterpolator(np.array(commands), np.array(speeds))


@dataclass(frozen=True)
class Stroke:
    """
    Speed factor along the stroke shared by both directions, with end cushions.

    ``interp(y, knots, factors)``, flat beyond the end knots, times a factor falling
    linearly from 1 to ``cushion_factor`` over the last ``cushion`` degrees before the
    end knot the joint heads for (docs/interfaces.md section 1.3, ``stroke_geometry``).
    """

    knots: tuple[float, ...]
    factors: tuple[float, ...]
    cushion: float = 0.0
    cushion_factor: float = 1.0

    def factor(self, angle: float, direction: float) -> float:
        """Return the factor at ``angle`` for motion of sign ``direction``."""
        value = float(np.interp(angle, self.knots, self.factors))
        if self.cushion > 0.0 and direction != 0.0:
            left = self.knots[-1] - angle if direction > 0.0 else angle - self.knots[0]
            share = min(max(left / self.cushion, 0.0), 1.0)
            value *= self.cushion_factor + (1.0 - self.cushion_factor) * share
        return value


@dataclass(frozen=True)
class Joint:
    """
    One joint: its map, timing, lags, stops and the factors on its speed.

    Parameters
    ----------
    speed_map : SpeedMap
        Steady speed of a command.
    delay : float
        Dead time of motion in the positive direction, s (and of both, unless
        ``delay_negative`` is set).
    delay_negative : float or None
        Dead time of motion in the negative direction, s.
    lag : float
        Time constant of a first-order lag of the speed, s (0: none).
    spool_lag : float
        Time constant of a first-order lag of the command before the map, s (0: none).
    stops : tuple[float, float] or None
        End stops of the actuator, deg.
    play : float
        Total play between actuator and sensor, deg.
    gravity : tuple[float, float] or None
        ``(amplitude, phase)``: speed times ``1 + amplitude cos(y + phase)`` moving up,
        ``1 - amplitude cos(y + phase)`` moving down.
    stroke : Stroke or None
        Factor along the stroke shared by both directions.
    load_factor : callable or None
        ``f(load, direction)``: speed factor of the measured load.
    sharing : tuple[float, float, float, float, float] or None
        ``(limit, full_positive, full_negative, other_positive, other_negative)``: the
        pump's flow in full demands of this joint, its speeds that count as a full demand,
        the other joints' speeds that do: the speed becomes ``w min(1, limit / (own
        demand + the others' demand))``.
    mode : tuple[float, float] or None
        ``(frequency, damping)``, Hz and ratio: the link rings on the oil column behind
        the actuator, ``y'' = w^2 (x - y) - 2 damping w y'``, ``w = 2 pi frequency``.
    noise : float
        Angle sensor noise, standard deviation, deg.

    """

    speed_map: SpeedMap
    delay: float = 0.1
    delay_negative: float | None = None
    lag: float = 0.0
    spool_lag: float = 0.0
    stops: tuple[float, float] | None = None
    play: float = 0.0
    gravity: tuple[float, float] | None = None
    stroke: Stroke | None = None
    load_factor: Callable[[float, float], float] | None = None
    sharing: tuple[float, float, float, float, float] | None = None
    mode: tuple[float, float] | None = None
    noise: float = 0.02


@dataclass(frozen=True)
class Machine:
    """
    Joints of one machine, on one pump.

    Parameters
    ----------
    joints : tuple[Joint, ...]
        The joints, in the order of the command columns.
    dt : float
        Sample period, s.
    names : tuple[str, ...]
        Joint names.

    """

    joints: tuple[Joint, ...]
    dt: float = 0.01
    names: tuple[str, ...] = field(default=('joint', 'other', 'third'))


class _State:
    """The state of one joint while it is driven."""

    def __init__(self, joint: Joint, h: float, angle: float, command: float,
                 steps: int) -> None:
        self.joint = joint
        before = joint.speed_map.speed(command)
        self.spool = command
        self.spool_pole = math.exp(-h / joint.spool_lag) if joint.spool_lag > 0.0 else 0.0
        self.lag_pole = math.exp(-h / joint.lag) if joint.lag > 0.0 else 0.0
        self.speed = before
        # The link reads ``angle``; moving steadily at w it trails the actuator by
        # 2 d w / w_n (its spring then pulls it at the damper's force).
        self.link = angle
        self.link_speed = before
        lead = 0.0
        if joint.mode is not None:
            frequency, damping = joint.mode
            lead = 2.0 * damping * before / (2.0 * math.pi * frequency)
        self.actuator = angle + lead
        self.moved = 0.0
        self.offset = 0.0
        self.up = int(round(joint.delay / h))
        down = joint.delay if joint.delay_negative is None else joint.delay_negative
        self.down = int(round(down / h))
        # Spool positions at every sub-step so far, for the dead times.
        self.history = np.full(steps + max(self.up, self.down) + 1, command, dtype=float)
        self.lead = max(self.up, self.down)

    def target(self, index: int) -> float:
        """Speed the map gives the spool positions of the two dead times, deg/s."""
        rate = self.joint.speed_map.speed
        up = rate(float(self.history[self.lead + index - self.up]))
        down = rate(float(self.history[self.lead + index - self.down]))
        return max(up, 0.0) + min(down, 0.0)

    @property
    def sensor(self) -> float:
        """Return the angle the sensor reads: the actuator's plus the play's offset."""
        low, high = _low_high(self.joint)
        return min(max(self.link + self.offset, low), high)

    def drift(self, angle: float, speed: float) -> float:
        """Angle speed of the actuator at ``angle`` for valve speed ``speed``, deg/s."""
        joint = self.joint
        direction = 1.0 if speed > 0.0 else -1.0 if speed < 0.0 else 0.0
        if joint.stroke is not None:
            speed *= joint.stroke.factor(angle, direction)
        if joint.gravity is not None:
            amplitude, phase = joint.gravity
            speed *= 1.0 + direction * amplitude * math.cos(math.radians(angle + phase))
        return speed


def simulate(machine: Machine, commands: np.ndarray, *, angles0: Sequence[float],
             load: np.ndarray | None = None) -> np.ndarray:
    """
    Simulate the machine; return the true (noise-free) sensor angles, shape (n, joints).

    ``commands[k]`` is in force over the interval ending at sample ``k`` (the first row
    is the command held before the run); ``load[k]`` likewise.
    """
    v = np.asarray(commands, dtype=float).reshape(len(commands), -1)
    n, count = v.shape
    h = machine.dt / SUBSTEPS
    states = [_State(joint, h, float(angles0[j]), float(v[0, j]), n * SUBSTEPS)
              for j, joint in enumerate(machine.joints)]
    out = np.empty((n, count))
    out[0] = [state.link for state in states]
    for k in range(1, n):
        _sample(states, v[k], k, None if load is None else float(load[k]), h)
        out[k] = [s.sensor for s in states]
    return out


def _sample(states: Sequence[_State], v: Sequence[float], k: int, load: float | None,
            h: float) -> None:
    """Advance every joint over the interval ending at sample ``k`` under commands ``v``."""
    for step in range(SUBSTEPS):
        index = (k - 1) * SUBSTEPS + step + 1
        wanted = []
        for j, state in enumerate(states):
            joint = state.joint
            state.spool = state.spool_pole * state.spool + (1.0 - state.spool_pole) * v[j]
            state.history[state.lead + index] = state.spool
            target = state.target(index)
            # The lag's speed, averaged over the sub-step (exact for a held target).
            start = state.speed
            state.speed = target + (start - target) * state.lag_pole
            mean = target if state.lag_pole == 0.0 else target + (start - target) * (
                joint.lag / h) * (1.0 - state.lag_pole)
            if joint.load_factor is not None and load is not None and mean != 0.0:
                mean *= joint.load_factor(load, 1.0 if mean > 0.0 else -1.0)
            wanted.append(mean)
        moved = [s.moved for s in states]
        for j, (state, speed) in enumerate(zip(states, wanted)):
            sharing = state.joint.sharing
            if sharing is not None and speed != 0.0:
                limit, full_up, full_down, other_up, other_down = sharing
                demand = speed / full_up if speed > 0.0 else -speed / full_down
                demand += sum(max(m, 0.0) / other_up - min(m, 0.0) / other_down
                              for i, m in enumerate(moved) if i != j)
                speed *= min(1.0, limit / demand)
            _advance(state, speed, h)


class GeneratedPlant:
    """
    One joint of the generator stepped one sample at a time: a plant of ``run_loop``.

    ``angle`` is the noisy reading, ``true_angle`` the sensor's angle without noise;
    ``step`` holds a command over the next sample (at most ``samples`` of them).
    """

    def __init__(self, joint: Joint, y0: float, *, dt: float = 0.01, rest: float = 0.0,
                 samples: int = 20_000, seed: int = 0) -> None:
        self.h = dt / SUBSTEPS
        self.state = _State(joint, self.h, y0, rest, samples * SUBSTEPS)
        self.rng = np.random.default_rng([seed, 17])
        self.k = 0
        self.true_angle = self.state.sensor
        self.angle = self.true_angle + float(self.rng.normal(0.0, joint.noise))

    def step(self, command: float) -> None:
        """Hold ``command`` over the next sample."""
        self.k += 1
        _sample([self.state], [float(command)], self.k, None, self.h)
        self.true_angle = self.state.sensor
        self.angle = self.true_angle + float(self.rng.normal(0.0, self.state.joint.noise))


def _low_high(joint: Joint) -> tuple[float, float]:
    return joint.stops if joint.stops is not None else (-math.inf, math.inf)


def _advance(state: _State, speed: float, h: float) -> None:
    """Move the actuator over one sub-step (midpoint rule), then its stops and the play."""
    low, high = _low_high(state.joint)
    previous = state.actuator
    middle = previous + 0.5 * h * state.drift(previous, speed)
    state.actuator = min(max(previous + h * state.drift(middle, speed), low), high)
    state.moved = (state.actuator - previous) / h
    link = state.link
    if state.joint.mode is None:
        state.link = state.actuator
    else:
        _ring(state, previous, state.moved, h)
    half = 0.5 * state.joint.play
    if half > 0.0:
        state.offset = min(max(state.offset - (state.link - link), -half), half)


def _ring(state: _State, start: float, speed: float, h: float) -> None:
    """Move the link on its spring over one sub-step (RK4), the actuator from ``start``."""
    assert state.joint.mode is not None
    frequency, damping = state.joint.mode
    w = 2.0 * math.pi * frequency

    def slope(t: float, y: float, u: float) -> tuple[float, float]:
        return u, w * w * (start + speed * t - y) - 2.0 * damping * w * u

    y, u = state.link, state.link_speed
    k1 = slope(0.0, y, u)
    k2 = slope(0.5 * h, y + 0.5 * h * k1[0], u + 0.5 * h * k1[1])
    k3 = slope(0.5 * h, y + 0.5 * h * k2[0], u + 0.5 * h * k2[1])
    k4 = slope(h, y + h * k3[0], u + h * k3[1])
    state.link = y + h / 6.0 * (k1[0] + 2.0 * k2[0] + 2.0 * k3[0] + k4[0])
    state.link_speed = u + h / 6.0 * (k1[1] + 2.0 * k2[1] + 2.0 * k3[1] + k4[1])


def record(machine: Machine, commands: np.ndarray, *, angles0: Sequence[float],
           load: np.ndarray | None = None, joint: int = 0, seed: int = 0,
           source: str = 'generated') -> Record:
    """
    Simulate and return joint ``joint``'s record: stamps with jitter, noisy angles.

    The other joints' angles (noisy too) are the record's ``others``; ``load`` is kept.
    """
    true = simulate(machine, commands, angles0=angles0, load=load)
    rng = np.random.default_rng([seed, 11])
    n = true.shape[0]
    noisy = true + rng.normal(0.0, 1.0, true.shape) * np.array(
        [j.noise for j in machine.joints])
    t = EPOCH + machine.dt * (np.arange(1, n + 1) + rng.uniform(-0.05, 0.05, n))
    v = np.asarray(commands, dtype=float).reshape(n, -1)
    others = [i for i in range(true.shape[1]) if i != joint]
    return Record(t, v[:, joint], noisy[:, joint], machine.names[joint], source, origin=EPOCH,
                  load=None if load is None else np.asarray(load, dtype=float),
                  others=noisy[:, others] if others else None,
                  other_joints=tuple(machine.names[i] for i in others))

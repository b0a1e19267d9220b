"""
The physics plant: joints sharing one pump, simulated over a command array (methods 11).

``commands[k]`` is in force over the interval ending at sample ``k`` (methods 3.4);
:func:`simulate_plant` and :class:`PlantSimulator` give the same trajectory.
"""

from __future__ import annotations

from dataclasses import dataclass
import math
from typing import Sequence

from hydro_sdp.core.arrays import FloatArray
from hydro_sdp.core.errors import DataError
from hydro_sdp.core.model.timing import SamplePeriod
from hydro_sdp.core.synthetic.physics.hydraulics import Actuator
from hydro_sdp.core.synthetic.physics.oil_column import OilColumn
from hydro_sdp.core.synthetic.physics.plant import Machine
from hydro_sdp.core.synthetic.physics.supply import Supply
from hydro_sdp.core.synthetic.physics.valve import metering_area, Spool, spool_travel
import numpy as np
from scipy.signal import bilinear, lfilter, lfilter_zi


@dataclass(frozen=True, eq=False)
class PlantRun:
    """
    What a simulation of the plant gives, one row per sample.

    Parameters
    ----------
    names : tuple[str, ...]
        Joint names, one per column.
    angles : FloatArray
        Measured joint angles, degrees, shape (n, joints).
    speeds : FloatArray
        Joint speed the cylinders set, deg/s (before the link's compliance and noise).
    extensions : FloatArray
        Cylinder extensions from fully retracted, mm.
    pressures : FloatArray or None
        Piston-side and rod-side pressures, bar, shape (n, joints, 2), when asked for.

    """

    names: tuple[str, ...]
    angles: FloatArray
    speeds: FloatArray
    extensions: FloatArray
    pressures: FloatArray | None = None


def _stop_filter(frequency: float, damping: float,
                 dt: SamplePeriod) -> tuple[FloatArray, FloatArray]:
    """Discrete ``w^2 / (s^2 + 2 d w s + w^2)`` (bilinear, prewarped at ``w``)."""
    w = 2.0 * math.pi * frequency
    fs = w / (2.0 * math.tan(w * dt / 2.0))
    b, a = bilinear([w * w], [1.0, 2.0 * damping * w, w * w], fs)
    return np.asarray(b, dtype=np.float64), np.asarray(a, dtype=np.float64)


def _check(machine: Machine, commands: FloatArray) -> FloatArray:
    v = np.asarray(commands, dtype=np.float64)
    if v.ndim == 1 and len(machine.joints) == 1:
        v = v[:, None]
    if v.ndim != 2 or v.shape[1] != len(machine.joints):
        raise DataError(f'commands must have shape (samples, {len(machine.joints)}), '
                        f'got {v.shape}')
    bad = np.argwhere(~np.isfinite(v))
    if bad.size:
        raise DataError(f'{len(bad)} commands are not finite (first at sample {bad[0][0]})')
    return v


def _initial(machine: Machine, actuators: Sequence[Actuator],
             angles0: Sequence[float] | None, before: Sequence[float] | None
             ) -> tuple[list[float], list[float]]:
    count = len(actuators)
    if angles0 is not None and len(angles0) != count:
        raise DataError(f'angles0 needs {count} values, got {len(angles0)}')
    if before is not None and len(before) != count:
        raise DataError(f'command_before needs {count} values, got {len(before)}')
    extensions = [act.stroke / 2.0 if angles0 is None else act.geometry.extension(angles0[i])
                  for i, act in enumerate(actuators)]
    commands = [joint.valve.neutral if before is None else float(before[i])
                for i, joint in enumerate(machine.joints)]
    return extensions, commands


def _blocked(actuators: Sequence[Actuator], areas: Sequence[float],
             extensions: Sequence[float], columns: Columns) -> bool:
    """Whether no cylinder can move (spool closed or driving it into its end): speeds all 0."""
    return not any(columns) and all(act.blocked(area, s) for act, area, s
                                    in zip(actuators, areas, extensions))


#: Each joint's oil column, None where the pressures settle at every sample.
Columns = Sequence[OilColumn | None]


def _columns(machine: Machine, actuators: Sequence[Actuator],
             extensions: Sequence[float]) -> list[OilColumn | None]:
    return [None if joint.compressibility is None else OilColumn(joint, act, s)
            for joint, act, s in zip(machine.joints, actuators, extensions)]


def _next_turn(areas: FloatArray) -> list[int]:
    """For each sample, the next one where an area changes sign, opens or closes (n if none)."""
    n = areas.shape[0]
    turns = np.flatnonzero(np.any(np.diff(np.sign(areas), axis=0) != 0.0, axis=1)) + 1
    following = np.append(turns, n)[np.searchsorted(turns, np.arange(n), side='right')]
    return following.tolist()


def _advance(supply: Supply, areas: Sequence[float], extensions: list[float],
             dt: SamplePeriod, columns: Columns) -> list[float]:
    """Move every cylinder over one sample; return the speeds the pump allows (m/s)."""
    moved = supply.speeds(areas, extensions)
    for i, (act, speed, column) in enumerate(zip(supply.actuators, moved, columns)):
        if column is None:
            extensions[i] = min(max(extensions[i] + dt * speed, 0.0), act.stroke)
        else:
            extensions[i] = column.advance(areas[i], speed, dt)
    return moved


def simulate_plant(machine: Machine, commands: FloatArray, dt: float, *,
                   angles0: Sequence[float] | None = None,
                   command_before: Sequence[float] | None = None,
                   seed: int | None = 0, noise: bool = True,
                   pressures: bool = False) -> PlantRun:
    """
    Simulate the machine for a command array.

    ``commands``: commands, shape (samples, joints) or 1-D for one joint, valve units.
    ``dt``: sample period, s.
    ``angles0``: angles at sample 0, degrees (None: mid-stroke).
    ``command_before``: command in force before sample 0 per joint (None: each valve's neutral).
    ``seed``: seed of the sensor noise.
    """
    dt = SamplePeriod(dt)
    v = _check(machine, commands)
    n, count = v.shape
    actuators = [Actuator(joint, machine.pump) for joint in machine.joints]
    extensions, before = _initial(machine, actuators, angles0, command_before)
    supply = Supply(actuators, machine.pump)
    columns = _columns(machine, actuators, extensions)
    held: list[list[tuple[float, float]]] = []
    areas = np.column_stack([
        metering_area(joint.valve, spool_travel(joint.valve, v[:, i], dt,
                                                command_before=before[i]))
        for i, joint in enumerate(machine.joints)])
    path = np.full((n, count), np.nan)
    speed = np.zeros((n, count))
    if n:
        path[0] = extensions
    table = areas.tolist()
    following = _next_turn(areas)
    moved, rows, where = [], [], []
    k = 1
    while k < n:
        if _blocked(actuators, table[k], extensions, columns):
            # Nothing moves until a spool closes, opens or reverses: skip to that sample.
            k = following[k]
            continue
        rows.append(k)
        moved.append(_advance(supply, table[k], extensions, dt, columns))
        where.append(list(extensions))
        if pressures and any(columns):
            held.append([(math.nan, math.nan) if c is None else c.pressures for c in columns])
        k += 1
    if rows:
        speed[rows] = moved
        path[rows] = where
    # Between the samples that move, the cylinders stay where they were: carry the last value.
    index = np.where(np.isnan(path[:, 0]), 0, np.arange(n))
    path = path[np.maximum.accumulate(index)]
    kinematic = np.column_stack([act.geometry.angles(path[:, i])
                                 for i, act in enumerate(actuators)])
    joint_speed = np.zeros((n, count))
    if n > 1:
        joint_speed[1:] = np.diff(kinematic, axis=0) / dt
    angles = np.empty((n, count))
    for i, joint in enumerate(machine.joints):
        b, a = _stop_filter(joint.stop_frequency, joint.stop_damping, dt)
        angles[:, i], _ = lfilter(b, a, kinematic[:, i], zi=lfilter_zi(b, a) * kinematic[0, i])
    if noise:
        rng = np.random.default_rng(seed)
        angles += rng.standard_normal((n, count)) * np.array(
            [joint.noise for joint in machine.joints])
    chambers = None
    if pressures:
        chambers = np.array([[act.pressures(table[k][i], path[k - 1 if k else 0, i],
                                            speed[k, i]) for i, act in enumerate(actuators)]
                             for k in range(n)]).reshape(n, count, 2)
        if held:
            # The oil columns' own pressures (every sample is a row: none is skipped).
            states = np.array(held)
            dynamic = [i for i, column in enumerate(columns) if column is not None]
            chambers[1:, dynamic] = states[:, dynamic]
    return PlantRun(machine.names, angles, joint_speed, path * 1e3, chambers)


class PlantSimulator:
    """
    Step the plant one sample at a time, as :func:`simulate_plant` does for the same seed.

    ``dt``: sample period, s.
    ``angles0``: angles at the first sample, degrees (None: mid-stroke).
    ``command_before``: commands in force up to and including the first sample.
    ``seed``: seed of the sensor noise.
    """

    def __init__(self, machine: Machine, dt: float, *,
                 angles0: Sequence[float] | None = None,
                 command_before: Sequence[float] | None = None,
                 seed: int | None = 0, noise: bool = True) -> None:
        self.machine = machine
        self.dt = SamplePeriod(dt)
        self._actuators = [Actuator(joint, machine.pump) for joint in machine.joints]
        self.extensions, before = _initial(machine, self._actuators, angles0, command_before)
        self._supply = Supply(self._actuators, machine.pump)
        self._columns = _columns(machine, self._actuators, self.extensions)
        self._spools = [Spool(joint.valve, self.dt, before[i])
                        for i, joint in enumerate(machine.joints)]
        filters = [_stop_filter(joint.stop_frequency, joint.stop_damping, self.dt)
                   for joint in machine.joints]
        # Python floats: the same arithmetic as on numpy scalars, without their overhead.
        self._filters = [(b.tolist(), a.tolist()) for b, a in filters]
        self._sigma = [joint.noise if noise else 0.0 for joint in machine.joints]
        self._rng = np.random.default_rng(seed) if noise else None
        kinematic = [act.geometry.angle(s) for act, s in zip(self._actuators, self.extensions)]
        self._state = [(lfilter_zi(b, a) * x).tolist() for (b, a), x in zip(filters, kinematic)]
        self._kinematic = kinematic
        self._angles = self._measure(kinematic)
        self.speeds = [0.0] * len(self._actuators)
        #: Piston-side and rod-side pressure of each joint over the last sample, bar.
        self.pressures = [act.pressures(0.0, s, 0.0)
                          for act, s in zip(self._actuators, self.extensions)]
        self.samples = 0

    def _measure(self, kinematic: Sequence[float]) -> list[float]:
        out = []
        for (b, a), z, x in zip(self._filters, self._state, kinematic):
            # lfilter's transposed direct form II, so both paths agree.
            y = b[0] * x + z[0]
            z[0] = b[1] * x - a[1] * y + z[1]
            z[1] = b[2] * x - a[2] * y
            out.append(y)
        if self._rng is not None:
            draws = self._rng.standard_normal(len(out))
            out = [y + float(d) * s for y, d, s in zip(out, draws, self._sigma)]
        return out

    @property
    def angles(self) -> list[float]:
        """Angles the sensors read now, degrees."""
        return list(self._angles)

    @property
    def angle_limits(self) -> list[tuple[float, float]]:
        """Joint angles at the stroke ends, degrees, per joint."""
        return [act.geometry.angle_limits for act in self._actuators]

    def step(self, commands: Sequence[float]) -> list[float]:
        """Issue one command per joint (valve units); return the next angles, degrees."""
        if len(commands) != len(self._actuators):
            raise DataError(f'step needs {len(self._actuators)} commands, got {len(commands)}')
        if not all(math.isfinite(c) for c in commands):
            raise DataError(f'commands must be finite, got {list(commands)}')
        travel = [spool.step(c) for spool, c in zip(self._spools, commands)]
        areas = [spool.area(x) for spool, x in zip(self._spools, travel)]
        previous = self._kinematic
        before = list(self.extensions)
        moved = [0.0] * len(areas)
        if not _blocked(self._actuators, areas, self.extensions, self._columns):
            moved = _advance(self._supply, areas, self.extensions, self.dt, self._columns)
        # What the chambers' pressure sensors read over the sample (as simulate_plant's).
        self.pressures = [act.pressures(area, extension, speed) if column is None
                          else column.pressures for act, area, extension, speed, column
                          in zip(self._actuators, areas, before, moved, self._columns)]
        # A cylinder that did not move keeps its angle.
        kinematic = [p if s == b else act.geometry.angle(s) for act, s, b, p
                     in zip(self._actuators, self.extensions, before, previous)]
        self._kinematic = kinematic
        self.speeds = [(x - p) / self.dt for x, p in zip(kinematic, previous)]
        self._angles = self._measure(kinematic)
        self.samples += 1
        return self.angles

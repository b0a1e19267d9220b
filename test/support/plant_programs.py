"""
Records of the physics plant for the plant grid (:mod:`support.plant_grid`).

* :func:`variant`: a joint of the shipped presets (``config/physics_*.yaml``) in one of
  its command units, its valve's dead time and spool lag drawn for the case;
* :func:`strokes`: constant duties held from one stroke end to the other, both ways;
* :func:`levels`: random duties (and rests at the neutral) held 0.5-3 s, turning back
  before the stops.

Both programs step the plant sample by sample (:class:`PlantSimulator`), so that a
second joint on the same pump can move at random levels of its own while the first
runs its program (its angle is the record's ``others``), and so that the first
joint's piston-side pressure can be logged as the record's ``load`` (bar), as a
pressure sensor on that chamber reads it.

The second joint rests at its neutral for a share of its holds (:data:`PARTNER_REST`),
drawn as the first joint's rests of :func:`levels` are: an operator moves the other
joint some of the time, not all of it. A partner that never rests slows every stroke
of the first joint alike, and flow sharing is then indistinguishable from a slower
valve: no data could name it.

"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Sequence

from hydro_sdp.core.model.records import Record
from hydro_sdp.core.synthetic.physics.linkage import Geometry
from hydro_sdp.core.synthetic.physics.machine import PlantSimulator
from hydro_sdp.core.synthetic.physics.plant import Joint, Machine
from hydro_sdp.core.synthetic.physics.runs import duty_command
from hydro_sdp.io.documents import shipped_config
from hydro_sdp.io.plant_files import load_machine
import numpy as np

DT = 0.01

#: Joints and units of the grid: (joint, units) -> (preset, valve neutral and limits or
#: None for the preset's own). The volt boom is the boom's valve driven by +-10 V.
VARIANTS: dict[tuple[str, str], tuple[str, tuple[float, tuple[float, float]] | None]] = {
    ('arm', 'signed_percent'): ('physics_arm.yaml', None),
    ('arm', 'percent'): ('physics_arm_pwm.yaml', None),
    ('boom', 'signed_percent'): ('physics_boom.yaml', None),
    ('boom', 'volt'): ('physics_boom.yaml', (0.0, (-10.0, 10.0))),
}

#: The joint that shares the pump with each joint when ``flow_sharing`` is hidden.
PARTNER = {'arm': 'physics_boom.yaml', 'boom': 'physics_arm.yaml'}
#: Share of the second joint's holds spent at its neutral (the operator moves it some of
#: the time; one that never rests would make the shared pump look like a slower valve).
PARTNER_REST = 0.4


def _with_valve(joint: Joint, valve: tuple[float, tuple[float, float]] | None,
                dead_time: float, time_constant: float) -> Joint:
    changes: dict[str, object] = {'dead_time': dead_time, 'time_constant': time_constant}
    if valve is not None:
        changes.update(neutral=valve[0], limits=valve[1])
    return replace(joint, valve=replace(joint.valve, **changes))


def variant(joint: str, units: str, rng: np.random.Generator, *, power: bool = False,
            partner: bool = False, ringing: bool = False) -> Machine:
    """
    Return the plant of one joint in one unit, its valve's timing drawn.

    Parameters
    ----------
    joint, units : str
        A key of :data:`VARIANTS`.
    rng : numpy.random.Generator
        Draws: the dead time (0.12-0.3 s) and the spool lag (0.12-0.35 s: pilot stages
        from brisk to slow).
    power : bool
        The boom of ``config/physics_boom_power.yaml`` instead: its valve without
        pressure compensation, on a pump whose power binds (only for the boom).
    partner : bool
        Whether the other joint of :data:`PARTNER` sits on the same pump (second).
    ringing : bool
        The boom of ``config/physics_boom_compressible.yaml`` instead: its link rings on a
        soft oil column at about 2 Hz (only for the boom).

    Returns
    -------
    Machine
        The plant; the joint of the grid first.

    """
    preset, valve = VARIANTS[(joint, units)]
    if power:
        preset = 'physics_boom_power.yaml'
    if ringing:
        preset = 'physics_boom_compressible.yaml'
    machine = load_machine(shipped_config(preset))
    first = _with_valve(machine.joints[0], valve, float(rng.uniform(0.12, 0.3)),
                        float(rng.uniform(0.12, 0.35)))
    joints = (first,)
    if partner:
        joints += (load_machine(shipped_config(PARTNER[joint])).joints[0],)
    return replace(machine, joints=joints)


class _Other:
    """
    Random duties of the second joint and rests at its neutral, held 0.5-3 s.

    A share :data:`PARTNER_REST` of the holds rests; the others head away from the
    nearer stop more often than not, as :func:`levels` does for the first joint.
    """

    def __init__(self, machine: Machine, rng: np.random.Generator) -> None:
        self.machine, self.rng = machine, rng
        self.limits = Geometry(machine.joints[1]).angle_limits
        self.neutral = machine.joints[1].valve.neutral
        self.command, self.left = self.neutral, 0

    def command_at(self, angle: float) -> float:
        """Return the command over the next sample, at the joint's ``angle``."""
        if self.left <= 0:
            low, high = self.limits
            sign = 1.0 if self.rng.random() > (angle - low) / (high - low) else -1.0
            self.command = self.neutral if self.rng.random() < PARTNER_REST else duty_command(
                self.machine, 1, sign * self.rng.uniform(35.0, 100.0))
            self.left = int(round(self.rng.uniform(0.5, 3.0) / DT))
        self.left -= 1
        return self.command


@dataclass
class _Run:
    """One record being made: the simulator, what it gave, the other joint."""

    machine: Machine
    sim: PlantSimulator
    other: _Other | None
    commands: list[list[float]]
    angles: list[list[float]]
    pressures: list[float]

    def step(self, command: float) -> None:
        both = [command] if self.other is None else [
            command, self.other.command_at(self.angles[-1][1])]
        self.commands.append(both)
        self.angles.append(self.sim.step(both))
        self.pressures.append(self.sim.pressures[0][0])

    def record(self, source: str, pressure: bool) -> Record:
        c, a = np.array(self.commands), np.array(self.angles)
        machine = self.machine
        return Record(DT * np.arange(1, len(c) + 1), c[:, 0], a[:, 0], machine.names[0], source,
                      load=np.array(self.pressures) if pressure else None,
                      others=a[:, 1:] if self.other is not None else None,
                      other_joints=machine.names[1:] if self.other is not None else ())


def _start(machine: Machine, angle: float, seed: int) -> _Run:
    rng = np.random.default_rng([seed, 1])
    angles0 = [angle] + [float(np.mean(Geometry(j).angle_limits)) for j in machine.joints[1:]]
    neutral = [j.valve.neutral for j in machine.joints]
    sim = PlantSimulator(machine, DT, angles0=angles0, command_before=neutral, seed=seed)
    other = _Other(machine, rng) if len(machine.joints) > 1 else None
    return _Run(machine, sim, other, [neutral], [sim.angles], [sim.pressures[0][0]])


def strokes(machine: Machine, duties: Sequence[float], seed: int, *,
            pressure: bool = False, rest: float = 1.0, on_stop: float = 1.0,
            longest: float = 40.0) -> list[Record]:
    """
    Constant duties held from one stroke end to the other, each way, one record each.

    Each run rests ``rest`` s at its starting end, then holds the duty until the
    cylinder reaches the other end and ``on_stop`` s beyond, or ``longest`` s.

    Parameters
    ----------
    machine : Machine
        The plant; its first joint runs the program (a second one moves at random).
    duties : sequence of float
        Duty magnitudes, percent of the travel from neutral to the limit.
    seed : int
        Seed of the noise and of the other joint's levels (the next runs count up).
    pressure : bool
        Whether each record's ``load`` is the piston-side pressure, bar.
    rest, on_stop, longest : float
        Durations, s.

    Returns
    -------
    list[Record]
        Extending runs first, then retracting ones.

    """
    low, high = Geometry(machine.joints[0]).angle_limits
    stroke = machine.joints[0].cylinder.stroke * 1e-3
    made = []
    for sign, start in ((1.0, low), (-1.0, high)):
        for duty in duties:
            run = _start(machine, start, seed + len(made))
            neutral = machine.joints[0].valve.neutral
            for _ in range(int(round(rest / DT))):
                run.step(neutral)
            command = duty_command(machine, 0, sign * duty)
            beyond = None
            for k in range(int(round(longest / DT))):
                run.step(command)
                ends = run.sim.extensions[0]
                if beyond is None and (ends >= stroke if sign > 0 else ends <= 0.0):
                    beyond = k + int(round(on_stop / DT))
                if beyond is not None and k >= beyond:
                    break
            made.append(run.record(f'stroke {sign * duty:+g} % #{seed + len(made)}', pressure))
    return made


def levels(machine: Machine, seconds: float, seed: int, *, pressure: bool = False,
           rest_share: float = 0.2) -> Record:
    """
    Random duties of 35-100 % held 0.5-3 s, some rests at the neutral, turning back at the stops.

    Parameters
    ----------
    machine : Machine
        The plant; its first joint runs the program (a second one moves at random).
    seconds : float
        Length, s.
    seed : int
        Seed of the levels, the holds and the noise.
    pressure : bool
        Whether the record's ``load`` is the piston-side pressure, bar.
    rest_share : float
        Share of the holds spent at the neutral.

    Returns
    -------
    Record
        The run.

    """
    rng = np.random.default_rng([seed, 2])
    low, high = Geometry(machine.joints[0]).angle_limits
    run = _start(machine, 0.5 * (low + high), seed)
    neutral = machine.joints[0].valve.neutral
    total = int(round(seconds / DT))
    while len(run.commands) < total:
        angle = run.angles[-1][0]
        # Head away from the nearer stop more often than not; turn back 10 % before it.
        sign = 1.0 if rng.random() > (angle - low) / (high - low) else -1.0
        command = neutral if rng.random() < rest_share else duty_command(
            machine, 0, sign * rng.uniform(35.0, 100.0))
        for _ in range(min(int(round(rng.uniform(0.5, 3.0) / DT)), total - len(run.commands))):
            angle = run.angles[-1][0]
            margin = 0.1 * (high - low)
            if command != neutral and ((sign > 0 and angle > high - margin) or (
                    sign < 0 and angle < low + margin)):
                command = neutral
            run.step(command)
    return run.record(f'levels #{seed}', pressure)

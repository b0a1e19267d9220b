"""
Experiments on the physics plant shaped like those recorded on real machines (methods 11).

Full strokes, step-and-return and random levels; duties are percent of the travel from
neutral to the limit on the side of the motion (positive extends).
"""

from __future__ import annotations

from dataclasses import replace
from typing import Sequence

from hydro_sdp.core.errors import ConfigurationError
from hydro_sdp.core.model.records import Record
from hydro_sdp.core.model.timing import SamplePeriod
from hydro_sdp.core.synthetic.physics.linkage import Geometry
from hydro_sdp.core.synthetic.physics.machine import PlantSimulator, simulate_plant
from hydro_sdp.core.synthetic.physics.plant import Joint, Machine
import numpy as np


def duty_command(machine: Machine, joint: int, duty: float) -> float:
    """Command in the valve's units for a signed ``duty`` in percent (-100..100) of ``joint``."""
    if not -100.0 <= duty <= 100.0:
        raise ConfigurationError(f'duty must lie in [-100, 100] %, got {duty}')
    valve = machine.joints[joint].valve
    limit = valve.limits[1] if duty >= 0.0 else valve.limits[0]
    return valve.neutral + abs(duty) / 100.0 * (limit - valve.neutral)


def _record(machine: Machine, joint: int, commands: np.ndarray, angles: np.ndarray,
            dt: SamplePeriod, source: str) -> Record:
    t = dt * np.arange(1, commands.shape[0] + 1)
    return Record(t, commands[:, joint], angles[:, joint], machine.joints[joint].name, source)


def _mid(joint: Joint) -> float:
    low, high = Geometry(joint).angle_limits
    return 0.5 * (low + high)


def _neutral(machine: Machine, samples: int) -> np.ndarray:
    return np.tile([joint.valve.neutral for joint in machine.joints], (samples, 1))


def full_stroke_runs(machine: Machine, dt: float, duties: Sequence[float], *, joint: int = 0,
                     rest: float = 1.0, on_stop: float = 1.2, longest: float = 240.0,
                     seed: int = 0) -> list[Record]:
    """
    Constant-duty runs from one end stop to the other and on against it, both directions.

    ``dt``: sample period, s.
    ``duties``: duty magnitudes, percent (each run once per direction).
    ``rest``, ``on_stop``, ``longest``: rest at the start, drive beyond the stop, longest run; s.
    ``seed``: seed of the first run's noise (the next runs use the following seeds).
    Returns: extending runs first (in the order of ``duties``), then retracting runs.
    """
    dt = SamplePeriod(dt)
    low, high = Geometry(machine.joints[joint]).angle_limits
    records: list[Record] = []
    for sign, start in ((1.0, low), (-1.0, high)):
        for duty in duties:
            command = duty_command(machine, joint, sign * abs(duty))
            n_rest = int(round(rest / dt))
            commands = _neutral(machine, n_rest + int(round(longest / dt)))
            commands[n_rest:, joint] = command
            angles0 = [_mid(j) for j in machine.joints]
            angles0[joint] = start
            run = simulate_plant(machine, commands, dt, angles0=angles0, seed=seed + len(records))
            stroke = machine.joints[joint].cylinder.stroke
            ends = run.extensions[:, joint]
            reached = np.flatnonzero(ends >= stroke if sign > 0 else ends <= 0.0)
            reached = reached[reached > n_rest]
            stop = commands.shape[0] if not reached.size else min(
                commands.shape[0], int(reached[0]) + int(round(on_stop / dt)))
            records.append(_record(machine, joint, commands[:stop], run.angles[:stop], dt,
                                   f'full stroke {sign * abs(duty):+g} %'))
    return records


def _hold(sim: PlantSimulator, commands: list[list[float]], angles: list[list[float]],
          command: list[float], samples: int) -> None:
    for _ in range(samples):
        commands.append(list(command))
        angles.append(sim.step(command))


def step_and_return(machine: Machine, dt: float, duties: Sequence[float], *, joint: int = 0,
                    hold: float = 2.0, rest: float = 1.0, return_duty: float = 60.0,
                    seed: int = 0) -> Record:
    """
    Step from mid-stroke and back: each step is followed by a return at one fixed duty.

    ``dt``: sample period, s.
    ``duties``: signed step duties, percent.
    ``hold``, ``rest``: step and rest durations, s.
    ``return_duty``: duty magnitude of every return move, percent.
    """
    dt = SamplePeriod(dt)
    neutral = [j.valve.neutral for j in machine.joints]
    home = _mid(machine.joints[joint])
    sim = PlantSimulator(machine, dt, angles0=[_mid(j) for j in machine.joints],
                         command_before=neutral, seed=seed)
    commands, angles = [list(neutral)], [sim.angles]
    n_rest, n_hold = int(round(rest / dt)), int(round(hold / dt))
    for duty in duties:
        _hold(sim, commands, angles, neutral, n_rest)
        step = list(neutral)
        step[joint] = duty_command(machine, joint, duty)
        _hold(sim, commands, angles, step, n_hold)
        _hold(sim, commands, angles, neutral, n_rest)
        back = list(neutral)
        sign = 1.0 if angles[-1][joint] < home else -1.0
        back[joint] = duty_command(machine, joint, sign * abs(return_duty))
        for _ in range(int(round(60.0 / dt))):
            if (angles[-1][joint] - home) * sign >= 0.0:
                break
            _hold(sim, commands, angles, back, 1)
    _hold(sim, commands, angles, neutral, n_rest)
    return _record(machine, joint, np.array(commands), np.array(angles), dt,
                   'step and return')


def random_levels(machine: Machine, dt: float, duration: float, *, joint: int = 0,
                  duties: tuple[float, float] = (35.0, 100.0),
                  holds: tuple[float, float] = (0.5, 3.0), seed: int = 0,
                  pressure: bool = False) -> Record:
    """
    Random duties held for random times, turning back before the stops.

    ``dt``: sample period, s.
    ``duration``: length of the run, s.
    ``duties``: range of duty magnitudes, percent.
    ``holds``: range of hold times, s.
    ``seed``: seed of the levels, the holds and the sensor noise.
    ``pressure``: whether the record's ``load`` is the joint's piston-side pressure, bar.
    """
    dt = SamplePeriod(dt)
    rng = np.random.default_rng(seed)
    neutral = [j.valve.neutral for j in machine.joints]
    low, high = Geometry(machine.joints[joint]).angle_limits
    sim = PlantSimulator(machine, dt, angles0=[_mid(j) for j in machine.joints],
                         command_before=neutral, seed=seed)
    commands, angles = [list(neutral)], [sim.angles]
    pressures = [sim.pressures[joint][0]]
    total = int(round(duration / dt))
    while len(commands) < total:
        # Head away from the nearer stop more often than not.
        upward = (angles[-1][joint] - low) / (high - low)
        sign = 1.0 if rng.random() > upward else -1.0
        level = list(neutral)
        level[joint] = duty_command(machine, joint, sign * rng.uniform(*duties))
        for _ in range(min(int(round(rng.uniform(*holds) / dt)), total - len(commands))):
            _hold(sim, commands, angles, level, 1)
            pressures.append(sim.pressures[joint][0])
    record = _record(machine, joint, np.array(commands), np.array(angles), dt, 'random levels')
    return replace(record, load=np.array(pressures)) if pressure else record

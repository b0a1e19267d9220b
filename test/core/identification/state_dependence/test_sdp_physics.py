"""The SDP analysis on the physics plant (valve, pump, cylinder, linkage: not an SDP model)."""

from dataclasses import replace
from typing import Sequence

from hydro_sdp.core.identification.identify import identify
from hydro_sdp.core.identification.state_dependence import analyse
from hydro_sdp.core.model.records import Record
from hydro_sdp.core.synthetic.physics.linkage import Geometry
from hydro_sdp.core.synthetic.physics.machine import PlantSimulator
from hydro_sdp.core.synthetic.physics.plant import Machine
from hydro_sdp.core.synthetic.physics.runs import duty_command
from hydro_sdp.io.documents import shipped_config
from hydro_sdp.io.plant_files import load_machine
import numpy as np
import pytest
from support.plant_levels import plant_levels

pytestmark = [pytest.mark.slow]

DT = 0.01
#: Time since 1970 the records are stamped from, s.
EPOCH = 1.76e9


def step_experiments(machine: Machine, duties: Sequence[float], *, hold: float = 2.5,
                     margin: float = 15.0, seed: int = 0) -> list[Record]:
    """
    One record per signed duty: rest, the duty held, rest; as a careful experimenter runs them.

    Each step starts ``margin`` inside the stop behind it and is let go ``margin`` before
    the stop ahead (or after ``hold``), so no stop holds the joint while it is driven.
    """
    low, high = Geometry(machine.joints[0]).angle_limits
    records = []
    for i, duty in enumerate(duties):
        start = low + margin if duty > 0 else high - margin
        sim = PlantSimulator(machine, DT, angles0=[start], command_before=[0.0], seed=seed + i)
        command = duty_command(machine, 0, duty)
        v, y = [0.0], [sim.angles[0]]
        plan = [0.0] * 100 + [command] * int(round(hold / DT))
        for value in plan:
            if value != 0.0 and ((duty > 0 and y[-1] > high - margin)
                                 or (duty < 0 and y[-1] < low + margin)):
                break
            v.append(value)
            y.append(sim.step([value])[0])
        for _ in range(100):
            v.append(0.0)
            y.append(sim.step([0.0])[0])
        t = EPOCH + DT * np.arange(1, len(v) + 1)
        records.append(Record(t, np.array(v), np.array(y), machine.names[0],
                              f'step {duty:+g} %', origin=EPOCH))
    return records


def signed(duties: Sequence[float]) -> list[float]:
    return [sign * duty for duty in duties for sign in (1.0, -1.0)]


@pytest.mark.parametrize('preset', ['physics_arm.yaml', 'physics_boom.yaml'])
def test_steps_on_the_physics_plant_show_an_integrator_and_a_command_dependent_gain(preset):
    machine = load_machine(shipped_config(preset))
    records = step_experiments(machine, signed((40, 45, 50, 55, 60, 65, 70, 75, 80, 90, 100)))
    result = analyse(records, states=['command', 'angle', 'since_change'])
    assert result.a1 is not None and abs(result.a1.mean + 1.0) < 0.01
    first = result.states[0]
    assert first.state == 'command' and first.significant
    # The gain rises from the valve's overlap to full opening: near zero at 40 %, several
    # times larger past 70 % (the opening table of the preset).
    for entry in result.dependence('command'):
        size = np.abs(entry.values)
        assert np.median(entry.estimate[size <= 45]) < 0.3 * np.median(entry.estimate[size >= 75])


def levels(machine: Machine, duration: float, moving: Sequence[int], seed: int) -> Record:
    """Drive the joints in ``moving`` with random duties held 0.5-3 s, turning before stops."""
    c, a = plant_levels(machine, DT, duration, moving, seed)
    return Record(EPOCH + DT * np.arange(1, len(c) + 1), c[:, 0], a[:, 0], machine.names[0],
                  f'levels {seed}', origin=EPOCH, others=a[:, 1:],
                  other_joints=machine.names[1:])


def test_a_second_joint_on_the_same_pump_shows_the_others_speed_first():
    # The arm and the boom of the presets on the arm's pump; the arm identified alone, from
    # enough of the stroke that its model learns how the speed changes along it.
    arm = load_machine(shipped_config('physics_arm.yaml'))
    boom = load_machine(shipped_config('physics_boom.yaml'))
    machine = replace(arm, joints=(arm.joints[0], boom.joints[0]))
    alone = [levels(machine, 60.0, [0], seed) for seed in (1, 2, 3)]
    model = identify([Record(r.t, r.v, r.y, r.joint, r.source, r.origin) for r in alone]).model
    assert model.effect('stroke_geometry') is not None
    both = [levels(machine, 60.0, [0, 1], seed) for seed in (4, 5, 6)]
    result = analyse(both, model=model, states=['command', 'angle', 'others_speed'])
    first = result.states[0]
    assert first.state == 'others_speed' and first.significant
    # The arm slows while the boom draws from the pump: the ratio is about 1 with the boom
    # still and about 0.7 with it moving faster than 12 deg/s.
    for entry in result.dependence('others_speed', parameter='ratio'):
        still = entry.estimate[entry.values < 2.0]
        busy = entry.estimate[entry.values > 12.0]
        assert abs(np.mean(still) - 1.0) < 0.1
        assert np.mean(busy) < np.mean(still) - 0.15
    # Without the boom moving there is nothing to see.
    quiet = analyse(alone, model=model, states=['others_speed'])
    assert ('others_speed', 'takes one value only') in quiet.skipped or not any(
        e.significant and e.share > 0.05 for e in quiet.dependence('others_speed'))

"""The physics plant: known answers from orifices, geometry, pump, cushions, stops and presets."""

import copy
import math

from hydro_sdp.core.errors import ModelFileError
from hydro_sdp.core.synthetic.physics import Machine, PlantSimulator, simulate_plant
from hydro_sdp.core.synthetic.physics.hydraulics import Actuator
from hydro_sdp.core.synthetic.physics.linkage import Geometry
from hydro_sdp.core.synthetic.physics.plant import with_payload
from hydro_sdp.core.synthetic.physics.runs import (
    duty_command, full_stroke_runs, random_levels, step_and_return)
from hydro_sdp.core.synthetic.physics.valve import (
    metering_area, Spool, spool_command, spool_travel)
from hydro_sdp.io.documents import load_yaml, shipped_config
from hydro_sdp.io.plant_files import load_machine
import numpy as np
import pytest
import yaml

DT = 0.01
# Arm, in (extending), 40..100 % duty: the mean stroke speeds the preset was tuned to, deg/s
# (config/physics_arm.yaml's header; illustrative, not measured). A regression check of the
# preset: the known answers of the plant's physics are the orifice, geometry and pump tests.
ARM_IN = {40: 1.0, 50: 4.0, 60: 12.6, 70: 19.8, 80: 30.0, 90: 31.6, 100: 31.7}


@pytest.fixture(scope='module')
def arm_data():
    return load_yaml(shipped_config('physics_arm.yaml'))


@pytest.fixture(scope='module')
def arm(arm_data):
    return Machine.from_mapping(arm_data)


@pytest.fixture(scope='module')
def boom():
    return load_machine(shipped_config('physics_boom.yaml'))


@pytest.fixture(scope='module')
def arm_and_boom(arm, boom):
    return Machine(arm.pump, arm.joints + boom.joints)


def held(machine, duty, seconds, joint=0, lead=0.5):
    """Neutral for ``lead`` s, then ``duty`` on one joint, the others at neutral."""
    n_lead, n = int(lead / DT), int((lead + seconds) / DT)
    commands = np.tile([j.valve.neutral for j in machine.joints], (n, 1))
    commands[n_lead:, joint] = duty_command(machine, joint, duty)
    return commands


def mean_stroke_speed(record, low, high):
    """Mean speed over the central 90 % of the travel, deg/s."""
    frac = (record.y - low) / (high - low)
    if record.v[-1] < 0:
        frac = 1.0 - frac
    start, stop = np.argmax(frac > 0.05), np.argmax(frac > 0.95)
    return 0.9 * (high - low) / ((stop - start) * DT)


def test_steady_cylinder_speed_is_orifice_flow_over_piston_area(arm):
    # 70 % duty: spool at 0.7, notch area 7.13 mm^2, 20 bar across it.
    run = simulate_plant(arm, held(arm, 70.0, 2.0), DT, angles0=[-20.0], noise=False)
    speed = np.diff(run.extensions[:, 0])[-20:] / DT / 1e3
    flow = 0.7 * 7.13e-6 * math.sqrt(2.0 * 20e5 / 860.0)
    expected = flow / (math.pi / 4.0 * 0.070 ** 2)
    np.testing.assert_allclose(speed, expected, rtol=1e-5)
    assert flow < 32.4e-3 / 60.0
    # Retracting: the annulus area and the retract notches (0.67 of the table).
    run = simulate_plant(arm, held(arm, -70.0, 2.0), DT, angles0=[20.0], noise=False)
    speed = np.diff(run.extensions[:, 0])[-20:] / DT / 1e3
    annulus = math.pi / 4.0 * (0.070 ** 2 - 0.040 ** 2)
    np.testing.assert_allclose(speed, -0.67 * flow / annulus, rtol=1e-5)


def test_joint_speed_follows_the_triangle(arm):
    geometry = Geometry(arm.joints[0])
    # At angle 0 the triangle's angle is 90 deg: L = sqrt(a^2 + b^2), arm = a b / L.
    length = math.hypot(1.0, 0.28)
    assert geometry.moment_arm(geometry.extension(0.0)) == pytest.approx(0.28 / length,
                                                                         rel=1e-12)
    assert geometry.extension(0.0) == pytest.approx(length - 0.826, rel=1e-12)
    run = simulate_plant(arm, held(arm, 70.0, 4.0), DT, angles0=[-40.0], noise=False)
    cylinder = np.diff(run.extensions[:, 0]) / DT / 1e3
    k = int(np.argmax(run.angles[1:, 0] > 0.0))
    at_zero = math.degrees(cylinder[k] / (0.28 / length))
    assert run.speeds[k + 1, 0] == pytest.approx(at_zero, rel=5e-3)
    # Slower where the moment arm is longer: the ratio is the triangle's.
    k2 = int(np.argmax(run.angles[1:, 0] > -25.0))
    ratio = run.speeds[k + 1, 0] / run.speeds[k2 + 1, 0]
    arms = geometry.moment_arm(geometry.extension(-25.0)) / (0.28 / length)
    assert ratio == pytest.approx(arms, rel=1e-2)


def test_no_motion_inside_the_overlap(arm):
    for duty in (-37.0, -10.0, 10.0, 37.0):
        run = simulate_plant(arm, held(arm, duty, 10.0), DT, angles0=[0.0], noise=False)
        assert np.all(run.angles[:, 0] == run.angles[0, 0])
        assert np.all(run.speeds == 0.0)
    run = simulate_plant(arm, held(arm, 38.5, 10.0), DT, angles0=[0.0], noise=False)
    assert run.angles[-1, 0] > run.angles[0, 0] + 1.0


def test_dead_time_then_first_order_spool(arm):
    valve = arm.joints[0].valve
    commands = np.r_[np.zeros(10), np.full(200, 100.0)]
    travel = spool_travel(valve, commands, DT, command_before=0.0)
    # 0.25 s dead time: the spool starts 25 samples after the step (sample 10).
    assert np.all(travel[:35] == 0.0) and travel[35] > 0.0
    # First-order lag of 0.1 s: 10-90 % rise in 2.2 time constants.
    rise = (np.argmax(travel >= 0.9) - np.argmax(travel >= 0.1)) * DT
    assert rise == pytest.approx(2.2 * 0.1, abs=0.015)


def test_flow_sharing_scales_both_joints_to_the_pump(arm_and_boom):
    machine = arm_and_boom
    n = 100
    commands = np.tile([80.0, 80.0], (n, 1))
    together = simulate_plant(machine, commands, DT, angles0=[-40.0, -10.0], noise=False,
                              command_before=[80.0, 80.0])
    actuators = [Actuator(j, machine.pump) for j in machine.joints]
    speeds = np.diff(together.extensions, axis=0)[-1] / DT / 1e3
    flows = [speeds[0] * actuators[0].piston, speeds[1] * actuators[1].piston]
    assert sum(flows) == pytest.approx(32.4e-3 / 60.0, rel=1e-9)
    for i in range(2):
        alone_commands = commands.copy()
        alone_commands[:, 1 - i] = 0.0
        alone = simulate_plant(machine, alone_commands, DT, angles0=[-40.0, -10.0],
                               noise=False, command_before=alone_commands[0])
        speed_alone = np.diff(alone.extensions[:, i])[-1] / DT / 1e3
        assert speed_alone * actuators[i].piston < 32.4e-3 / 60.0
        assert speeds[i] < 0.8 * speed_alone
    # Both joints get the same share of what they asked for.
    demands = [actuators[i].demand(a, together.extensions[-2, i] / 1e3)[0]
               for i, a in enumerate((0.7 * 10.85e-6, 0.7 * 11.5e-6))]
    assert speeds[0] / demands[0] == pytest.approx(speeds[1] / demands[1], rel=1e-6)


def test_cushions_slow_the_last_degrees(arm):
    low, high = Geometry(arm.joints[0]).angle_limits
    run = simulate_plant(arm, held(arm, 100.0, 6.0), DT, angles0=[low], noise=False)
    ends = run.extensions[:, 0]
    speed = np.abs(run.speeds[:, 0])
    cushion = np.flatnonzero((ends > 373.0 - 18.0) & (ends < 373.0))
    before = speed[cushion[0] - 1]
    assert before > 30.0
    assert speed[cushion[-1]] < 0.35 * before
    # The throttled stretch is a few degrees of the joint.
    assert 2.0 < high - run.angles[cushion[0], 0] < 8.0


def test_relief_caps_pressure_and_stalls_a_heavy_load(boom):
    low, _ = Geometry(boom.joints[0]).angle_limits
    run = simulate_plant(boom, held(boom, 100.0, 8.0), DT, angles0=[low], noise=False,
                         pressures=True)
    assert run.pressures is not None
    assert run.pressures.max() <= 210.0 + 1e-9
    # Driven against the stop, the pump goes to relief on the piston side.
    assert run.pressures[-1, 0, 0] == pytest.approx(210.0)
    heavy = with_payload(boom, 4000.0)
    stalled = simulate_plant(heavy, held(heavy, 100.0, 3.0), DT, angles0=[0.0], noise=False,
                             pressures=True)
    assert np.all(stalled.angles[:, 0] <= stalled.angles[0, 0] + 1e-12)
    assert stalled.pressures[-1, 0, 0] == pytest.approx(210.0)
    # A load near relief is slowed by it: the pump cannot hold the margin, the inlet
    # chamber sits between relief - margin and relief.
    area = 0.7 * 16.0e-6
    free = Actuator(boom.joints[0], boom.pump)
    near = Actuator(with_payload(boom, 1700.0).joints[0], boom.pump)
    extension = free.geometry.extension(0.0)
    speed, _ = near.demand(area, extension)
    assert 0.0 < speed < 0.5 * free.demand(area, extension)[0]
    assert 190.0 < near.pressures(area, extension, speed)[0] < 210.0


def test_arm_preset_moves_at_the_speeds_it_was_tuned_to(arm):
    low, high = Geometry(arm.joints[0]).angle_limits
    runs = full_stroke_runs(arm, DT, list(ARM_IN), longest=120.0)
    extending = runs[:len(ARM_IN)]
    for (duty, target), record in zip(ARM_IN.items(), extending):
        assert mean_stroke_speed(record, low, high) == pytest.approx(target, rel=0.15), duty


@pytest.mark.parametrize('name, band', [('physics_arm.yaml', (1.3, 1.6)),
                                        ('physics_boom.yaml', (1.4, 2.3))])
def test_speed_along_the_stroke_changes_the_same_way_both_ways(name, band):
    machine = load_machine(shipped_config(name))
    low, high = Geometry(machine.joints[0]).angle_limits
    profiles = []
    for duty, start in ((70.0, low), (-70.0, high)):
        run = simulate_plant(machine, held(machine, duty, 20.0), DT, angles0=[start],
                             noise=False)
        frac = (run.angles[:, 0] - low) / (high - low)
        speed = np.abs(run.speeds[:, 0])
        middle = (frac > 0.1) & (frac < 0.9) & (speed > 0.0)
        assert band[0] <= speed[middle].max() / speed[middle].min() <= band[1]
        grid = np.linspace(0.15, 0.85, 8)
        order = np.argsort(frac[middle])
        profile = np.interp(grid, frac[middle][order], speed[middle][order])
        profiles.append(profile / profile.mean())
        # Slowing hard at the end: under 40 % of the mid-stroke speed when the stop is met.
        last = np.flatnonzero(speed > 0.0)[-1]
        assert speed[last] < 0.4 * np.median(speed[middle])
    np.testing.assert_allclose(profiles[0], profiles[1], rtol=0.08)


def test_end_stop_overshoot_and_bounce_like_real_stops(arm):
    low, high = Geometry(arm.joints[0]).angle_limits
    for duty, start in ((80.0, low), (100.0, low), (-80.0, high), (-100.0, high)):
        run = simulate_plant(arm, held(arm, duty, 8.0), DT, angles0=[start], noise=False)
        ends = run.extensions[:, 0]
        k = int(np.flatnonzero(ends >= 373.0 if duty > 0 else ends <= 0.0)[0])
        after = run.angles[k:, 0] * np.sign(duty)
        overshoot = after.max() - after[-1]
        assert 0.3 <= overshoot <= 0.7, duty
        bounce = -np.diff(after[np.argmax(after):]).min()
        assert 0.02 <= bounce <= 0.09, duty
        # It settles on the stop angle.
        assert after[-1] * np.sign(duty) == pytest.approx(high if duty > 0 else low, abs=1e-3)


def test_stepping_and_vectorised_simulation_agree(arm_and_boom):
    rng = np.random.default_rng(5)
    levels = rng.uniform(-100.0, 100.0, size=(40, 2))
    commands = np.repeat(levels, rng.integers(20, 120, size=40), axis=0)
    run = simulate_plant(arm_and_boom, commands, DT, angles0=[-10.0, 10.0],
                         command_before=commands[0], seed=3)
    sim = PlantSimulator(arm_and_boom, DT, angles0=[-10.0, 10.0],
                         command_before=commands[0], seed=3)
    stepped = [sim.angles] + [sim.step(row) for row in commands[1:].tolist()]
    np.testing.assert_allclose(np.array(stepped), run.angles, rtol=0.0, atol=1e-9)
    assert np.ptp(run.angles[:, 0]) > 20.0 and np.ptp(run.angles[:, 1]) > 20.0
    assert sim.speeds == pytest.approx(run.speeds[-1].tolist(), abs=1e-6)


@pytest.mark.parametrize('preset', ['physics_arm.yaml', 'physics_arm_pwm.yaml',
                                    'physics_boom.yaml'])
def test_the_stepped_spool_gives_the_arrays_bits(preset):
    # PlantSimulator maps one command and one travel at a time; simulate_plant whole arrays.
    valve = load_machine(shipped_config(preset)).joints[0].valve
    spool = Spool(valve, DT, valve.neutral)
    rng = np.random.default_rng(2)
    low, high = valve.limits
    commands = np.concatenate([rng.uniform(low - 10.0, high + 10.0, 2000),
                               [low, valve.neutral, high]])
    stepped = np.array([spool.command(c) for c in commands.tolist()])
    assert stepped.tobytes() == spool_command(valve, commands).tobytes()
    knots = np.array(spool.area.travels)
    travels = np.concatenate([rng.uniform(-1.0, 1.0, 2000), knots, -knots, [0.0]])
    stepped = np.array([spool.area(x) for x in travels.tolist()])
    assert stepped.tobytes() == metering_area(valve, travels).tobytes()


def test_programs_are_records_shaped_like_real_runs(arm):
    low, high = Geometry(arm.joints[0]).angle_limits
    runs = full_stroke_runs(arm, DT, [60.0], rest=1.0, on_stop=1.2)
    assert [r.source for r in runs] == ['full stroke +60 %', 'full stroke -60 %']
    for record, start, end in zip(runs, (low, high), (high, low)):
        assert record.t[0] == pytest.approx(DT) and record.joint == 'arm'
        assert np.all(record.v[:100] == 0.0) and record.v[-1] == pytest.approx(
            60.0 * np.sign(end - start))
        assert record.y[0] == pytest.approx(start, abs=0.01)
        # Ends 1.2 s after reaching the stop, resting on it.
        assert record.y[-1] == pytest.approx(end, abs=0.02)
    steps = step_and_return(arm, DT, [45.0, -45.0], hold=1.0, return_duty=50.0)
    middle = 0.5 * (low + high)
    assert steps.v.min() == pytest.approx(-50.0) and steps.v.max() == pytest.approx(50.0)
    # Back past the start by what moves during the dead time and the lag.
    assert abs(steps.y[-1] - middle) < 2.0
    levels = random_levels(arm, DT, 30.0, seed=2)
    assert len(levels) == 3000 and low - 1.0 <= levels.y.min() and levels.y.max() <= high + 1.0
    assert np.all((np.abs(levels.v[1:]) >= 35.0) & (np.abs(levels.v[1:]) <= 100.0))


def test_records_round_trip_through_a_bag(arm, tmp_path):
    from hydro_sdp.bags import read_record, write_bag

    record = full_stroke_runs(arm, DT, [100.0], longest=5.0)[0]
    path = write_bag(tmp_path / 'run', [record])
    back = read_record(path)
    np.testing.assert_allclose(back.y, record.y, atol=1e-9)
    np.testing.assert_array_equal(back.v, record.v)


def test_a_duty_valve_with_rest_at_fifty(arm_data):
    data = copy.deepcopy(arm_data)
    data['joints'][0]['valve'].update(neutral=50.0, limits=[0.0, 100.0])
    machine = Machine.from_mapping(data)
    assert duty_command(machine, 0, 40.0) == pytest.approx(70.0)
    assert duty_command(machine, 0, -40.0) == pytest.approx(30.0)
    run = simulate_plant(machine, held(machine, 70.0, 2.0), DT, angles0=[0.0], noise=False)
    original = simulate_plant(Machine.from_mapping(arm_data), held(
        Machine.from_mapping(arm_data), 70.0, 2.0), DT, angles0=[0.0], noise=False)
    np.testing.assert_allclose(run.angles, original.angles)
    rest = simulate_plant(machine, np.full(300, 50.0), DT, angles0=[0.0], noise=False)
    assert np.all(rest.angles == rest.angles[0])


@pytest.mark.parametrize('path, value, key', [
    (('pump', 'flow'), -1.0, 'pump.flow'),
    (('pump', 'margin'), 'high', 'pump.margin'),
    (('pump', 'relief_pressure'), 10.0, 'pump.relief_pressure'),
    (('joints', 0, 'valve', 'neutral'), 150.0, 'joints[0].valve.neutral'),
    (('joints', 0, 'valve', 'overlap'), 1.5, 'joints[0].valve.overlap'),
    (('joints', 0, 'valve', 'opening'), [[0.5, 2.0], [0.4, 3.0], [1.0, 4.0]],
     'joints[0].valve.opening[1][0]'),
    (('joints', 0, 'valve', 'opening'), [[0.5, 2.0], [1.0, 1.0]],
     'joints[0].valve.opening[1][1]'),
    (('joints', 0, 'valve', 'opening'), [[0.5, 2.0], [0.9, 3.0]], 'joints[0].valve.opening'),
    (('joints', 0, 'cylinder', 'rod'), 80.0, 'joints[0].cylinder.rod'),
    (('joints', 0, 'cylinder', 'stroke'), 900.0, 'joints[0].cylinder.stroke'),
    (('joints', 0, 'stop', 'damping'), 1.5, 'joints[0].stop.damping'),
    (('joints', 0, 'load', 'mass'), True, 'joints[0].load.mass'),
    (('joints', 0, 'linkage', 'colour'), 1.0, 'joints[0].linkage.colour'),
])
def test_bad_parameters_are_refused_naming_the_key(arm_data, path, value, key):
    data = copy.deepcopy(arm_data)
    target = data
    for part in path[:-1]:
        target = target[part]
    target[path[-1]] = value
    with pytest.raises(ModelFileError, match=key.replace('[', r'\[').replace(']', r'\]')):
        Machine.from_mapping(data)


def test_missing_keys_and_files_are_named(arm_data, tmp_path):
    data = copy.deepcopy(arm_data)
    del data['joints'][0]['cylinder']['bore']
    with pytest.raises(ModelFileError, match=r"missing required key 'joints\[0\].cylinder.bore'"):
        Machine.from_mapping(data)
    data = copy.deepcopy(arm_data)
    data['format'] = 'hydro_sdp/model/v1'
    with pytest.raises(ModelFileError, match="key 'format'"):
        Machine.from_mapping(data)
    bad = tmp_path / 'bad.yaml'
    data = copy.deepcopy(arm_data)
    data['joints'].append(copy.deepcopy(data['joints'][0]))
    bad.write_text(yaml.safe_dump(data))
    with pytest.raises(ModelFileError, match=r"bad.yaml: key 'joints': joint names repeat"):
        load_machine(bad)

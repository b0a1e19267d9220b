"""The pump's power limit and valves without compensation: orifice and power equations hold."""

from dataclasses import replace
import math

from hydro_sdp.core.errors import ModelFileError
from hydro_sdp.core.synthetic.physics import Machine, simulate_plant
from hydro_sdp.core.synthetic.physics.hydraulics import Actuator
from hydro_sdp.core.synthetic.physics.linkage import Geometry
from hydro_sdp.core.synthetic.physics.plant import with_payload
from hydro_sdp.core.synthetic.physics.runs import duty_command, random_levels
from hydro_sdp.core.synthetic.physics.supply import speeds
from hydro_sdp.io.documents import load_yaml, shipped_config
from hydro_sdp.io.plant_files import load_machine
import numpy as np
import pytest

DT = 0.01
RHO = 860.0


@pytest.fixture(scope='module')
def boom() -> Machine:
    return load_machine(shipped_config('physics_boom_power.yaml'))


def compensated(machine: Machine, power: float = 0.0) -> Machine:
    """Return the same machine with compensated valves and the given power limit."""
    joints = tuple(replace(j, valve=replace(j.valve, compensated=True)) for j in machine.joints)
    return replace(machine, pump=replace(machine.pump, power=power), joints=joints)


def held_speed(machine: Machine, duty: float, angle: float, joint: int = 0) -> float:
    """Steady cylinder speed, m/s, 1.5 s after a duty is applied from ``angle``."""
    n = 150
    commands = np.tile([j.valve.neutral for j in machine.joints], (n, 1))
    commands[:, joint] = duty_command(machine, joint, duty)
    run = simulate_plant(machine, commands, DT, angles0=[angle] * len(machine.joints),
                         noise=False, command_before=list(commands[0]))
    return float(np.diff(run.extensions[:, joint])[-1] / DT / 1e3)


def test_the_preset_reads_its_power_and_its_valve_without_compensation(boom):
    assert boom.pump.power == 3.0 and not boom.joints[0].valve.compensated
    plain = load_machine(shipped_config('physics_boom.yaml'))
    assert plain.pump.power == 0.0 and plain.joints[0].valve.compensated
    # At 150 bar the pump gives 3 kW / 150 bar = 12 l/min; its 33 l/min up to 54.5 bar.
    assert boom.pump.available(150e5) == pytest.approx(3e3 / 150e5)
    assert boom.pump.available(50e5) == pytest.approx(33e-3 / 60.0)


def test_without_compensation_the_flow_is_the_orifices_at_the_pressure_left(boom):
    actuator = Actuator(boom.joints[0], boom.pump)
    extension = actuator.geometry.extension(10.0)
    area = 0.7 * 11.5e-6        # 80 % duty: spool at 0.8, notch 11.5 mm^2, Cd 0.7
    supply = 120e5
    speed, flow = actuator.supplied(area, extension, supply)
    # Force balance with both orifices: p_s A_p - p_t A_a - F = rho/2 v^2 (A_p^3/a_i^2 +
    # A_a^3/a_o^2), a_o = 0.8 a_i (outlet_ratio).
    piston = math.pi / 4 * 0.080 ** 2
    annulus = piston - math.pi / 4 * 0.045 ** 2
    force = actuator.geometry.load_force(extension) + 1000.0
    drive = supply * piston - 2e5 * annulus - force
    expected = math.sqrt(drive / (RHO / 2 * (piston ** 3 / area ** 2 +
                                             annulus ** 3 / (0.8 * area) ** 2)))
    assert speed == pytest.approx(expected, rel=1e-12)
    assert flow == pytest.approx(expected * piston, rel=1e-12)
    # The inlet pressure it needs at that speed leaves exactly the drop the orifice takes.
    inlet = actuator.inlet_pressure(area, extension, speed)
    assert flow == pytest.approx(area * math.sqrt(2.0 * (supply - inlet) / RHO), rel=1e-9)
    # Below the load's pressure nothing passes (the load check valve).
    assert actuator.supplied(area, extension, 0.5 * inlet) == (0.0, 0.0)


def test_where_the_power_binds_flow_times_pressure_is_the_power(boom):
    heavy = with_payload(compensated(boom, power=3.0), 600.0)
    actuator = Actuator(heavy.joints[0], heavy.pump)
    extension = actuator.geometry.extension(10.0)
    area = 0.7 * 16.0e-6        # full duty
    speed = speeds([actuator], heavy.pump, [area], [extension])[0]
    # Compensated, the pump sets its pressure to the inlet's at the compensated speed plus
    # the margin; the flow it gives there is the power over that pressure, shared out.
    demand = actuator.demand(area, extension)[0]
    pressure = actuator.inlet_pressure(area, extension, demand) + 20e5
    assert speed * actuator.piston * pressure == pytest.approx(3e3, rel=1e-12)
    assert speed < 0.7 * demand
    # Without compensation the pump pressure falls below the load-sensing setting: it and
    # the flow meet on the power curve and on the orifice, both.
    open_valve = with_payload(boom, 600.0)
    found = speeds([Actuator(open_valve.joints[0], open_valve.pump)], open_valve.pump,
                   [area], [extension])[0]
    flow = found * actuator.piston
    supply = 3e3 / flow
    assert flow == pytest.approx(actuator.supplied(area, extension, supply)[1], rel=1e-9)
    assert supply < pressure and found > speed


def test_a_resisting_load_slows_the_joint_only_where_the_power_binds(boom):
    low, _ = Geometry(boom.joints[0]).angle_limits
    ratios = {}
    for duty in (55.0, 100.0):
        light = held_speed(with_payload(boom, 0.0), duty, low + 5.0)
        heavy = held_speed(with_payload(boom, 600.0), duty, low + 5.0)
        ratios[duty] = heavy / light
    # At 55 % duty the flow asked stays under 3 kW at either load; at full duty lifting
    # 600 kg the power binds: about x0.6-0.75 of the speed lifting nothing.
    assert ratios[55.0] == pytest.approx(1.0, abs=0.02)
    assert 0.55 < ratios[100.0] < 0.8


def test_without_compensation_a_lighter_joint_takes_more_than_its_share():
    arm = load_machine(shipped_config('physics_arm.yaml'))
    boom = load_machine(shipped_config('physics_boom.yaml'))
    both = Machine(replace(arm.pump, flow=80.0), arm.joints + boom.joints)
    open_valves = replace(both, joints=tuple(
        replace(j, valve=replace(j.valve, compensated=False)) for j in both.joints))
    actuators = [Actuator(j, both.pump) for j in both.joints]
    areas = [0.7 * 7.13e-6, 0.7 * 8.0e-6]      # 70 % duty on both
    extensions = [a.stroke / 2 for a in actuators]
    held = speeds(actuators, both.pump, areas, extensions)
    # Compensated, each gets its compensated flow (the pump gives 80 l/min).
    assert held == pytest.approx([a.demand(x, s)[0] for a, x, s in
                                  zip(actuators, areas, extensions)], rel=1e-12)
    free = speeds([Actuator(j, both.pump) for j in open_valves.joints], both.pump, areas,
                  extensions)
    pressures = [a.inlet_pressure(x, s, abs(v)) for a, x, s, v in
                 zip(actuators, areas, extensions, held)]
    lighter = int(np.argmin(pressures))
    # Without compensators the pump holds its margin over the heavier load only: the
    # lighter joint sees a larger drop and moves faster than compensated.
    assert abs(free[lighter]) > 1.05 * abs(held[lighter])
    assert abs(free[1 - lighter]) == pytest.approx(abs(held[1 - lighter]), rel=1e-6)


def test_random_levels_log_the_piston_pressure(boom):
    record = random_levels(boom, DT, 6.0, seed=1, pressure=True)
    assert record.load is not None and record.load.shape == record.v.shape
    assert 2.0 <= record.load.min() and record.load.max() <= 210.0
    assert random_levels(boom, DT, 2.0, seed=1).load is None


@pytest.mark.parametrize('key, value, message', [
    ('power', -1.0, "key 'pump.power': must be >= 0"),
    ('compensated', 'no', "key 'joints[0].valve.compensated': expected true or false"),
])
def test_bad_power_and_compensation_are_refused(key, value, message):
    data = load_yaml(shipped_config('physics_boom_power.yaml'))
    if key == 'power':
        data['pump'][key] = value
    else:
        data['joints'][0]['valve'][key] = value
    with pytest.raises(ModelFileError) as error:
        Machine.from_mapping(data)
    assert str(error.value).startswith(message)

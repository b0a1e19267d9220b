"""The oil column: the link on compressible oil rings at the hydraulic natural frequency."""

from dataclasses import replace
import math

from hydro_sdp.core.errors import ModelFileError
from hydro_sdp.core.synthetic.physics import Machine, PlantSimulator, simulate_plant
from hydro_sdp.core.synthetic.physics.hydraulics import Actuator
from hydro_sdp.core.synthetic.physics.oil_column import OilColumn
from hydro_sdp.io.documents import load_yaml, shipped_config
from hydro_sdp.io.plant_files import load_machine
import numpy as np
import pytest

DT = 0.01


@pytest.fixture(scope='module')
def ringing():
    return load_machine(shipped_config('physics_boom_compressible.yaml'))


def _frictionless(machine, gravity=True):
    joint = machine.joints[0]
    joint = replace(joint, cylinder=replace(joint.cylinder, friction=0.0),
                    compressibility=replace(joint.compressibility, viscous_friction=0.0))
    if not gravity:
        joint = replace(joint, load=replace(joint.load, mass=0.0, payload=0.0))
    return replace(machine, joints=(joint,))


def _ring(machine, extension, samples=500, kick=0.002):
    """Extensions of the sealed cylinder (spool closed) after the link is nudged."""
    joint = machine.joints[0]
    column = OilColumn(joint, Actuator(joint, machine.pump), extension)
    if joint.load.mass == 0.0 and joint.load.payload == 0.0:
        # Nothing to hold: both chambers charged to 50 bar, so that neither cavitates.
        column.p_piston = column.p_rod = 50e5
    column.gamma += kick
    return column, np.array([column.advance(0.0, 0.0, DT) for _ in range(samples)])


def _frequency(path, dt=DT):
    """Damped frequency from the zero crossings about the mean, Hz."""
    d = path - path.mean()
    sign = np.sign(d)
    crossings = np.flatnonzero(sign[1:] * sign[:-1] < 0)
    times = [(c + d[c] / (d[c] - d[c + 1])) * dt for c in crossings]
    return 1.0 / (2.0 * float(np.mean(np.diff(times))))


@pytest.mark.parametrize('share', [0.1, 0.5, 0.9])
def test_the_sealed_link_rings_at_merritts_hydraulic_natural_frequency(ringing, share):
    # k_h = beta (A_a^2 / V_a + A_b^2 / V_b), w_n = sqrt(k_h r^2 / J) (Merritt 1967): without
    # gravity or friction the only spring is the oil.
    machine = _frictionless(ringing, gravity=False)
    stroke = Actuator(machine.joints[0], machine.pump).stroke
    column, path = _ring(machine, share * stroke)
    assert _frequency(path) == pytest.approx(column.natural_frequency(share * stroke), rel=0.01)


def test_gravity_on_the_link_shifts_the_frequency_only_slightly(ringing):
    # The gravity moment changes with the angle (a small negative stiffness) and the moment
    # arm with the stroke: 1 % off the oil column's own frequency at mid-stroke.
    machine = _frictionless(ringing)
    stroke = Actuator(machine.joints[0], machine.pump).stroke
    column, path = _ring(machine, 0.5 * stroke)
    assert _frequency(path) == pytest.approx(column.natural_frequency(0.5 * stroke), rel=0.015)


def test_viscous_friction_damps_it_at_its_damping_ratio(ringing):
    joint = ringing.joints[0]
    machine = replace(ringing, joints=(replace(joint, cylinder=replace(joint.cylinder,
                                                                       friction=0.0)),))
    stroke = Actuator(joint, ringing.pump).stroke
    column, path = _ring(machine, 0.5 * stroke, samples=300)
    d = path - path[-50:].mean()
    peaks = [k for k in range(1, d.size - 1) if d[k] > d[k - 1] and d[k] >= d[k + 1]][:3]
    decrement = math.log(d[peaks[0]] / d[peaks[1]])
    zeta = decrement / math.sqrt(4.0 * math.pi ** 2 + decrement ** 2)
    assert zeta == pytest.approx(column.damping_ratio(0.5 * stroke), rel=0.1)
    assert 0.08 < zeta < 0.15          # lightly damped, as the preset says


def test_the_preset_boom_rings_about_two_hertz_after_it_stops_where_the_settled_one_does_not(
        ringing):
    # Lift at 80 % for 1.5 s, then close the valve: the ringing boom overshoots and swings at
    # the frequency of the oil column, the same boom with settled pressures barely moves.
    v = np.r_[np.zeros(30), np.full(150, 80.0), np.zeros(370)]
    settled = replace(ringing, joints=(replace(ringing.joints[0], compressibility=None),))
    soft = simulate_plant(ringing, v, DT, angles0=[-10.0], noise=False)
    hard = simulate_plant(settled, v, DT, angles0=[-10.0], noise=False)
    # The spool closes at about 2.05 s (its dead time and lag after the command's 1.8 s).
    tail = soft.angles[205:, 0]
    assert tail.max() - tail[-1] > 0.8 and tail[-1] - tail[:150].min() > 0.4
    assert hard.angles[205:, 0].max() - hard.angles[-1, 0] < 0.1
    joint = ringing.joints[0]
    rest = soft.extensions[-1, 0] * 1e-3
    column = OilColumn(joint, Actuator(joint, ringing.pump), rest)
    expected = column.natural_frequency(rest) * math.sqrt(1.0 - column.damping_ratio(rest) ** 2)
    assert 1.8 < expected < 2.3
    # Two swings before the seals' Coulomb friction holds it: the peaks half a second apart.
    peaks = [k for k in range(1, 120) if tail[k - 1] < tail[k] >= tail[k + 1]]
    assert 1.0 / ((peaks[1] - peaks[0]) * DT) == pytest.approx(expected, rel=0.1)


def test_held_at_one_command_it_moves_at_the_settled_plants_speed(ringing):
    # The inflow is the compensated valve's: once the pressures have settled the speed is
    # the quasi-static one (the stroke's mid-range, away from the cushions).
    v = np.r_[np.zeros(10), np.full(300, 70.0)]
    settled = replace(ringing, joints=(replace(ringing.joints[0], compressibility=None),))
    soft = simulate_plant(ringing, v, DT, angles0=[-15.0], noise=False)
    hard = simulate_plant(settled, v, DT, angles0=[-15.0], noise=False)
    assert np.mean(soft.speeds[250:300, 0]) == pytest.approx(
        np.mean(hard.speeds[250:300, 0]), rel=0.02)


def test_stepping_and_the_whole_run_agree_with_the_oil_column(ringing):
    rng = np.random.default_rng(3)
    v = np.repeat(rng.choice([-80.0, -50.0, 0.0, 60.0, 90.0], 8), 40)
    whole = simulate_plant(ringing, v, DT, angles0=[5.0], command_before=[v[0]], seed=2,
                           pressures=True)
    sim = PlantSimulator(ringing, DT, angles0=[5.0], command_before=[v[0]], seed=2)
    stepped = [sim.angles] + [sim.step([c]) for c in v[1:]]
    np.testing.assert_allclose(np.array(stepped), whole.angles, atol=1e-9)
    assert sim.pressures[0] == pytest.approx(tuple(whole.pressures[-1, 0]))


def test_the_oil_column_needs_a_compensated_valve():
    data = load_yaml(shipped_config('physics_boom_compressible.yaml'))
    data['joints'][0]['valve']['compensated'] = False
    with pytest.raises(ModelFileError, match='joints\\[0\\].compressibility.*compensated'):
        Machine.from_mapping(data)
    data['joints'][0]['valve']['compensated'] = True
    data['joints'][0]['compressibility']['bulk_modulus'] = 0.0
    with pytest.raises(ModelFileError, match='compressibility.bulk_modulus'):
        Machine.from_mapping(data)

"""The map's own inverse as the IDZ: tables of every map family, modes, edges, the controller."""

from dataclasses import replace

from hydro_sdp.core.control.controller_spec import ControllerSpec, design_from_model
from hydro_sdp.core.control.idz import InverseDeadZone
from hydro_sdp.core.control.idz_design import chord_idz, default_form, idz_for_model
from hydro_sdp.core.control.idz_recalibration import recalibrated_idz
from hydro_sdp.core.control.idz_table import chord_as_table, TableInverseDeadZone
from hydro_sdp.core.control.idz_table_design import table_idz
from hydro_sdp.core.control.loop_simulation import (
    LoopJoint, run_closed_loop, step_setpoints, valve_reversals)
from hydro_sdp.core.control.pip_controller import ControllerSettings, PipIdzController
from hydro_sdp.core.control.pip_design import PipGains
from hydro_sdp.core.errors import ConfigurationError, DataError, ModelFileError
from hydro_sdp.core.model.command_span import command_span
from hydro_sdp.core.model.effects import ValveLag
from hydro_sdp.core.model.joint_model import JointModel
from hydro_sdp.core.model.static_maps import PwlMap, shifted_map
from hypothesis import given, settings, strategies as st
import numpy as np
import pytest
from support.map_families import MODELS

PERIOD = 0.05
PAPER = PipGains((0.1261,), (0.12, 0.1261), 0.0061)


@pytest.mark.parametrize('kind', sorted(MODELS))
def test_the_table_inverts_the_map(kind):
    model = MODELS[kind]
    table = table_idz(model, PERIOD, beta=0.0)
    u, v = np.asarray(table.u), np.asarray(table.v)
    assert np.all(np.diff(v) > 0) and np.all(np.diff(u) >= 0) and len(u) <= 81
    low, high = command_span(model)
    assert v[0] == low or kind == 'pwl'
    # Edges: the map's own dead-zone where it has one, else the rest command.
    edges = model.dead_zone or (model.rest_command, model.rest_command)
    assert table.dead_zone == pytest.approx(edges)
    assert table.dead_zone[0] <= model.rest_command <= table.dead_zone[1]
    # The table's points lie on the map, and between them the inverse is close.
    np.testing.assert_allclose(u, PERIOD * model.rate(v), atol=1e-12)
    top = max(abs(u[0]), abs(u[-1]))
    for wanted in np.linspace(u[0], u[-1], 301):
        if abs(wanted) < 1e-9:
            continue
        command, branch = table.command(float(wanted))
        assert branch == np.sign(wanted)
        assert table.increment(command) == pytest.approx(wanted, abs=1e-9 * top)
        assert PERIOD * float(model.rate(command)) == pytest.approx(wanted, abs=0.02 * top)


def test_the_table_of_a_convex_valve_gives_small_corrections_the_chord_does_not():
    model = MODELS['power_sat']
    table = table_idz(model, PERIOD, beta=0.0)
    chord = chord_idz(model, PERIOD, beta=0.0)
    small = 0.1 * table.u[-1]                       # a tenth of full speed
    by_table = PERIOD * float(model.rate(table.command(small)[0]))
    by_chord = PERIOD * float(model.rate(chord.command(small)[0]))
    assert by_table == pytest.approx(small, rel=0.03)
    assert by_chord < 0.6 * small                   # the chord's promise is not kept


def test_default_forms_and_limits():
    assert [default_form(MODELS[k]) for k in ('sdp', 'sdp_dz', 'linear')] == ['chord'] * 3
    assert [default_form(MODELS[k]) for k in ('pwl', 'poly', 'power_sat')] == ['table'] * 3
    assert isinstance(idz_for_model(MODELS['sdp'], PERIOD), InverseDeadZone)
    spec = design_from_model(MODELS['power_sat'])
    assert isinstance(spec.idz, TableInverseDeadZone)
    assert spec.u_limits == spec.idz.u_range
    # A saturating map without input limits: the table ends at 99 % of saturation.
    bare = replace(MODELS['sdp'], input_limits=None)
    low, high = table_idz(bare, PERIOD, beta=0.0).u_range
    assert low == pytest.approx(-0.99 * 29.51 * PERIOD) and high == pytest.approx(
        0.99 * 38.87 * PERIOD)
    with pytest.raises(ConfigurationError, match='input_limits'):
        table_idz(replace(MODELS['linear'], input_limits=None), PERIOD, beta=0.0)
    with pytest.raises(ConfigurationError, match='rest command'):
        table_idz(MODELS['sdp_dz'], PERIOD, beta=0.0, v_range=(60.0, 100.0))


def test_a_map_that_does_not_move_one_way_has_no_table():
    still = JointModel('j', PwlMap((-10.0, 0.0, 5.0, 10.0), (0.0, 0.0, 0.0, 3.0)), 0.1)
    with pytest.raises(DataError, match='down'):
        table_idz(still, PERIOD, beta=0.0)


def test_default_band_covers_the_noise_and_keeps_the_smallest_correction():
    model = MODELS['pwl'].with_effect(ValveLag(0.12))
    quiet = design_from_model(model, noise_std=0.0).idz
    # 0.15 deg over 8 samples of delay and 0.12 s of lag at 0.05 s.
    assert quiet.beta == pytest.approx(0.15 / (8 + 0.12 / 0.05))
    noisy = design_from_model(model, noise_std=0.2).idz
    assert noisy.beta > 3 * quiet.beta
    # A map without a dead-zone needs no band; a chord keeps the paper's 0.05.
    assert design_from_model(MODELS['poly']).idz.beta == 0.0
    assert design_from_model(MODELS['sdp']).idz.beta == 0.05


J2_CHORD = InverseDeadZone((-1.3298, 1.3124), (1.1746, 2.3951), beta=0.05)


@pytest.mark.parametrize('mode', ['zero', 'hysteresis'])
def test_a_chord_is_a_table_of_two_points_per_branch(mode):
    chord = replace(J2_CHORD, mode=mode)
    table = chord_as_table(chord, (-10.0, 10.0))
    assert len(table.u) == 4 and table.slopes == pytest.approx(chord.slopes)
    chord_branch = table_branch = 0
    for u in np.r_[np.linspace(-3.0, 3.0, 241), np.linspace(0.2, -0.2, 41)]:
        expected, chord_branch = chord.command(float(u), chord_branch)
        got, table_branch = table.command(float(u), table_branch)
        inside = table.u[0] <= u <= table.u[-1]
        assert table_branch == chord_branch
        if inside:
            assert got == pytest.approx(expected, abs=1e-12)


def test_modes_near_zero():
    table = table_idz(MODELS['power_sat'], PERIOD, beta=0.05)
    low, high = table.dead_zone
    assert table.command(0.03) == (table.rest, 0) and table.command(-0.05) == (table.rest, 0)
    hysteresis = replace(table, mode='hysteresis')
    v, branch = hysteresis.command(0.2)
    assert branch == 1 and v > high
    v, branch = hysteresis.command(0.01, branch)         # inside the band: keeps the branch
    assert branch == 1 and high < v < hysteresis.command(0.2)[0]
    v, branch = hysteresis.command(-0.04, branch)        # the branch continued, floored
    assert branch == 1 and low <= v <= high
    v, branch = hysteresis.command(-0.06, branch)
    assert branch == -1 and v < low
    smooth = replace(table, mode='smooth')
    values = [smooth.command(float(u))[0] for u in np.linspace(-0.3, 0.3, 601)]
    assert np.all(np.diff(values) > -1e-9)               # monotone across the band
    assert smooth.command(0.3)[0] == pytest.approx(table.command(0.3)[0], abs=0.05)


def test_moved_edges_shift_a_branch_and_new_slopes_scale_it():
    table = table_idz(MODELS['power_sat'], PERIOD, beta=0.02)
    low, high = table.dead_zone
    moved = table.with_edges((low, high + 4.0))
    assert moved.dead_zone == pytest.approx((low, high + 4.0))
    for u in (0.1, 0.5, 1.0):
        assert moved.command(u)[0] == pytest.approx(table.command(u)[0] + 4.0)
        assert moved.command(-u)[0] == pytest.approx(table.command(-u)[0])
    scaled = table.with_slopes((table.slopes[0], 1.5 * table.slopes[1]))
    assert scaled.slopes == pytest.approx((table.slopes[0], 1.5 * table.slopes[1]))
    v = table.command(0.6)[0]
    assert scaled.increment(v) == pytest.approx(1.5 * table.increment(v))
    assert scaled.u_range[1] == pytest.approx(1.5 * table.u_range[1])
    with pytest.raises(ConfigurationError, match='reversed'):
        table.with_edges((high, low))
    with pytest.raises(ConfigurationError, match='rest command'):
        table.with_edges((2.0, 30.0))
    with pytest.raises(ConfigurationError, match='slopes'):
        table.with_slopes((0.0, 1.0))
    # Equal edges become one point, and back.
    linear = table_idz(MODELS['linear'], PERIOD, beta=0.0)
    assert linear.u.count(0.0) == 1 and linear.with_edges((-2.0, 3.0)).u.count(0.0) == 2


@pytest.mark.parametrize('u, v, message', [
    ((-1.0, 0.0, 1.0), (0.0, 2.0, 1.0), 'increase strictly'),
    ((-1.0, 0.5, 1.0), (0.0, 1.0, 2.0), 'u = 0'),
    ((-1.0, 0.0, 0.0, 0.0, 1.0), (0.0, 1.0, 2.0, 3.0, 4.0), 'u = 0'),
    ((0.0, 0.5, 1.0), (0.0, 1.0, 2.0), 'both signs'),
    ((-1.0, -2.0, 0.0, 1.0), (0.0, 1.0, 2.0, 3.0), 'each side'),
    ((-1.0, 0.0, 1.0), (0.0, float('nan'), 2.0), 'finite'),
    ((-1.0, 0.0), (0.0, 1.0), 'at least 3'),
])
def test_bad_tables_are_refused(u, v, message):
    with pytest.raises(ConfigurationError, match=message):
        TableInverseDeadZone(u, v, rest=v[1] if len(v) > 1 else 0.0)


def test_a_table_controller_file_round_trips_and_names_its_keys(tmp_path):
    spec = design_from_model(MODELS['power_sat'].with_effect(ValveLag(0.05)))
    data = spec.to_mapping()
    assert set(data['idz']) == {'mode', 'beta', 'rest', 'table'}
    assert ControllerSpec.from_mapping(data) == spec
    table = data['idz']['table']
    with pytest.raises(ModelFileError, match="unknown key 'dead_zone'.*follow from the table"):
        ControllerSpec.from_mapping({**data, 'idz': {**data['idz'], 'dead_zone': [-1, 1]}})
    with pytest.raises(ModelFileError, match='increase strictly'):
        ControllerSpec.from_mapping({**data, 'idz': {**data['idz'], 'table': {
            'u': table['u'], 'v': table['v'][::-1]}}})
    with pytest.raises(ModelFileError, match="key 'idz.table'"):
        ControllerSpec.from_mapping({**data, 'idz': {**data['idz'], 'table': [1, 2]}})
    with pytest.raises(ModelFileError, match="key 'idz.table.u"):
        ControllerSpec.from_mapping({**data, 'idz': {**data['idz'], 'table': {
            'u': ['fast'] + table['u'][1:], 'v': table['v']}}})


def test_the_controller_keeps_what_the_table_can_give():
    table = table_idz(MODELS['power_sat'], PERIOD, beta=0.02)
    controller = PipIdzController(ControllerSettings(PAPER, table))
    for _ in range(100):
        u, v = controller.step(90.0, 0.0)
    assert v == table.v[-1] and u == table.u_range[1]
    u, v = controller.step(-90.0, 0.0)                   # no wind-up to undo
    assert u < table.u_range[1]


def test_a_table_change_does_not_jump_the_command():
    table = table_idz(MODELS['power_sat'], PERIOD, beta=0.02)
    controller = PipIdzController(ControllerSettings(PAPER, table))
    for _ in range(30):
        u, v = controller.step(3.0, 0.0)
    assert table.dead_zone[1] + 5.0 < v < table.v[-1] - 10.0
    moved = table.with_edges((table.dead_zone[0], table.dead_zone[1] + 5.0))
    controller.update_idz(moved)
    assert moved.command(controller.last_u, 1)[0] == pytest.approx(v)
    assert abs(controller.step(3.0, 0.0)[1] - v) < 1.0


@settings(max_examples=200, deadline=None)
@given(st.lists(st.tuples(st.floats(-1e6, 1e6), st.floats(-1e6, 1e6)), min_size=1,
                max_size=40),
       st.sampled_from(['zero', 'smooth', 'hysteresis']), st.floats(0.0, 0.5))
def test_table_commands_are_finite_and_inside_the_valve(inputs, mode, beta):
    table = replace(table_idz(MODELS['pwl'], PERIOD, beta=0.0), mode=mode, beta=beta)
    controller = PipIdzController(ControllerSettings(PAPER, table, None, (-100.0, 100.0)))
    for setpoint, angle in inputs:
        u, v = controller.step(setpoint, angle)
        assert np.isfinite(u) and -100.0 <= v <= 100.0
        assert table.u_range[0] <= u <= table.u_range[1]


def test_a_recalibrated_table_stops_the_hunting_of_a_worn_valve(j2):
    # The J2 valve's dead-zone narrows by 0.3 V on each side (wear): its table now
    # over-compensates and the loop hunts; the edges the online identifier reports
    # (here the true ones, with the chord slopes it sends) shift the table back.
    worn = replace(j2, static_map=shifted_map(j2.static_map, (0.3, -0.3)))
    spec = design_from_model(j2, form='table', noise_std=0.01)
    recalibrated = recalibrated_idz(worn, worn.dead_zone, PERIOD)
    table = spec.idz.with_slopes(recalibrated.slopes).with_edges(recalibrated.dead_zone)
    assert table.dead_zone == pytest.approx(worn.dead_zone)
    levels = [20.0, 35.0, 15.0, 30.0]
    setpoint = step_setpoints(levels * 2, 4.0, 0.01)
    ends = []
    for idz in (spec.idz, table):
        controller = replace(spec, idz=idz).controller()
        trace = run_closed_loop([LoopJoint(worn, controller, setpoint, 20.0)], dt=0.01,
                                control_period=PERIOD, noise_std=0.01, seed=4)[0]
        tail = np.abs(trace.y - trace.setpoint).reshape(8, 400)[-4:, -50:]
        ends.append((float(tail.max()), valve_reversals(trace.v[-1600:], idz.rest)))
    (worst_before, reversals_before), (worst_after, reversals_after) = ends
    assert worst_before > 0.5 or reversals_before > 20
    assert worst_after < 0.5 and reversals_after < reversals_before

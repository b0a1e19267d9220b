"""
Identification from routine operation: an operator's joystick and closed loops, not experiments.

The joints are ``support.plain_joint`` (its own map: a linear rise from the dead-zone
rounded into saturation by ``tanh``, not one of the map families; its own delay and
integrator, stamps since 1970 with jitter), driven by an operator's joystick that changes
the command every 50 ms, or by a PIP-IDZ loop written from the equations
(``support.independent_loop``) reading a controller file. Nothing here is simulated by
the code under test.
"""

import math

from hydro_sdp.core.control.controller_spec import design_from_model
from hydro_sdp.core.errors import DataError
from hydro_sdp.core.identification.identify import identify
from hydro_sdp.core.identification.routine.detect import held_share, routine_operation
from hydro_sdp.core.identification.routine.increment_fit import fit_sdp_increments
from hydro_sdp.core.identification.routine.increments import increment_delay, increments_of
from hydro_sdp.core.identification.routine.speed_curve import speed_points
from hydro_sdp.core.identification.segmentation import segment_records
from hydro_sdp.core.model.joint_model import JointModel
from hydro_sdp.core.model.records import Record
from hydro_sdp.core.model.static_maps import sdp_rate, SdpDzMap
from hydro_sdp.io.controller_files import save_controller
import numpy as np
import pytest
from scipy.optimize import least_squares
from support.independent_loop import FileController, run_loop
from support.plain_joint import EPOCH, PlainJoint, PlainPlant, steps

VOLTS = PlainJoint()
#: A valve driven in percent duty resting at 50 %, with another delay.
PERCENT = PlainJoint(delay=8, dead_zone=(44.0, 57.0), slope=(2.0, 2.5),
                     saturation=(40.0, 50.0))


def edge_error(model, joint):
    return max(abs(a - b) for a, b in zip(model.dead_zone, joint.dead_zone))


@pytest.mark.parametrize(('joint', 'neutral', 'reach', 'seed'), [
    (VOLTS, 0.0, 4.0, 1), (VOLTS, 0.0, 4.0, 2), (PERCENT, 50.0, 40.0, 3)])
def test_an_operators_joystick_is_identified_from_its_increments(joint, neutral, reach, seed):
    record = joint.run_joystick(45.0, neutral=neutral, reach=reach, seed=seed)
    assert held_share([record], neutral, 50) < 0.05     # the command changes every 50 ms
    result = identify([record])
    assert result.route == 'routine'
    assert result.segmentation.rest == neutral
    assert result.model.delay == pytest.approx(joint.delay * joint.dt)
    assert edge_error(result.model, joint) < 0.1 * (1.0 if neutral == 0.0 else 10.0)
    # The speed measured along the command and the map agree where the joint moves.
    assert result.model.input_limits == (float(np.min(record.v)), float(np.max(record.v)))


def closed_loop_record(joint, controller_edges, tmp_path, seed=3):
    """Run a PIP-IDZ loop from a controller file, its IDZ at ``controller_edges``."""
    model = JointModel('plain', SdpDzMap(dead_zone=controller_edges, slope=(14.0, 18.0)),
                       delay=0.12, angle_limits=(-60.0, 70.0), input_limits=(-10.0, 10.0))
    path = tmp_path / f'controller_{seed}.yaml'
    save_controller(design_from_model(model), path)
    run = run_loop(FileController.read(path), PlainPlant(joint, 0.0, seed=seed), joint.dt,
                   [0.0, 20.0, -6.0, 46.0], 5.0)
    # The command decided at sample j is in force over the interval ending at j + 1.
    return Record(EPOCH + joint.dt * np.arange(1, run.v.size + 1), np.r_[0.0, run.v[:-1]],
                  run.measured, 'plain', 'loop', origin=EPOCH)


@pytest.mark.parametrize('controller_edges', [
    (-0.9, 0.8),        # the controller's IDZ at the true edges
    (-0.7, 0.6),        # inside them: commands the joint does not answer
])
def test_a_closed_loop_with_three_set_point_moves_gives_the_dead_zone(
        controller_edges, tmp_path):
    record = closed_loop_record(VOLTS, controller_edges, tmp_path)
    assert routine_operation([record], 0.0, 50)
    result = identify([record])
    assert result.route == 'routine'
    assert result.model.delay == pytest.approx(0.12)
    assert edge_error(result.model, VOLTS) < 0.1
    if controller_edges == (-0.7, 0.6):
        # Commands between the controller's edges and the true ones leave the joint still.
        assert result.model.undetermined == ()


def test_edges_in_commands_a_closed_loop_never_sent_are_bounds(tmp_path):
    # The controller's IDZ beyond the true edges: no command between rest and them.
    record = closed_loop_record(VOLTS, (-1.1, 1.0), tmp_path)
    model = identify([record]).model
    bounds = {entry.parameter: entry.bound for entry in model.undetermined}
    assert set(bounds) == {'dead_zone[0]', 'dead_zone[1]'}
    assert -1.3 < bounds['dead_zone[0]'][0] <= -1.1
    assert 1.0 <= bounds['dead_zone[1]'][1] < 1.2
    for (low, high), edge in zip(bounds.values(), VOLTS.dead_zone):
        assert low <= edge <= high


def test_step_experiments_still_take_the_experiments_route():
    record = VOLTS.run(steps([2.0, -2.0, 3.0, -3.0, 1.5, -1.5, 4.0, -4.0]))
    assert held_share([record], 0.0, 50) == 1.0
    result = identify([record])
    assert result.route == 'experiments'
    assert edge_error(result.model, VOLTS) < 0.1


def test_the_increment_fit_is_least_squares_over_every_increment():
    record = VOLTS.run_joystick(30.0, seed=4)
    segmentation = segment_records([record], max_delay=50)
    data = increments_of(segmentation.experiments, VOLTS.delay)
    points = speed_points(data, VOLTS.dt, 0.0)
    fit = fit_sdp_increments(data, VOLTS.dt, points, 0.0)

    def residuals(x):
        v_neg, c_neg, low, v_pos, c_pos, high = x
        rate = sdp_rate(data.command, v_neg, c_neg, low, v_pos, c_pos, high)
        return data.increment - VOLTS.dt * rate
    m = fit.static_map
    x = np.array([m.saturation_velocity[0], m.curvature[0], m.dead_zone[0],
                  m.saturation_velocity[1], m.curvature[1], m.dead_zone[1]])
    assert fit.cost == pytest.approx(0.5 * np.sum(residuals(x) ** 2), rel=1e-9)
    # An independent fit over every increment (not per distinct command) agrees.
    full = least_squares(residuals, x * np.r_[1.1, 0.9, 1.05, 0.9, 1.1, 0.95], x_scale='jac')
    np.testing.assert_allclose(full.x, x, rtol=1e-4)


@pytest.mark.parametrize('delay', [3, 20])
def test_the_delay_is_the_one_whose_command_explains_the_increments(delay):
    joint = PlainJoint(delay=delay)
    record = joint.run_joystick(30.0, seed=5)
    segmentation = segment_records([record], max_delay=50)
    found = increment_delay(segmentation.experiments, joint.dt, max_delay=50, rest=0.0)
    assert found.samples == delay
    assert found.explained.size == 50 and np.argmax(found.explained) == delay - 1


def test_an_operator_who_never_drives_down_is_told_what_was_never_seen():
    record = VOLTS.run_joystick(30.0, directions='up', seed=6, y0=-50.0)
    with pytest.raises(DataError, match=r'the joint never moved down: no command below rest 0 '
                                        r'was seen \(commands seen 0 \.\. 3\.\d+\), so the '
                                        r'dead-zone edge below rest cannot be placed'):
        identify([record])


def test_commands_inside_the_dead_zone_only_are_named_as_the_range_never_seen():
    rng = np.random.default_rng(7)
    # A command every 50 ms, up to 3.5 V up but never beyond -0.6 V down.
    levels = np.repeat(rng.uniform(-0.6, 3.5, 600), 5)
    levels[rng.random(levels.size) < 0.2] = 0.0
    record = VOLTS.run(np.r_[0.0, levels], y0=-55.0)
    lowest = f'{levels.min():.4g}'
    with pytest.raises(DataError, match=f'the joint never moved down: the commands below rest '
                                        f'reached only {lowest} and never moved it '
                                        f'measurably; commands below {lowest} were never seen'):
        identify([record])
    with pytest.raises(DataError, match=f'commands from {lowest} to the valve limit -10 were '
                                        'never seen'):
        identify([record], input_limits=(-10.0, 10.0))


def test_messages_say_where_the_limits_come_from(j2):
    record = VOLTS.run_joystick(30.0, seed=8)
    result = identify([record], angle_limits=(-60.0, 70.0))
    assert result.commands.angle_limits_from == 'given'
    assert result.commands.input_limits_from == 'data'
    assert result.model.angle_limits == (-60.0, 70.0)
    given = identify([record], input_limits=(-10.0, 10.0))
    assert given.commands.input_limits_from == 'given'
    assert given.model.input_limits == (-10.0, 10.0)
    assert math.isclose(given.commands.seen[1], float(np.max(record.v)))

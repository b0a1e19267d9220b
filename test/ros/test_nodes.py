"""The ROS nodes in-process: lockstep equals offline, safety, parameters, recalibration, bags."""

import math
import sqlite3
import time

from conftest import REPO
from hydro_sdp.bags import read_bag
from hydro_sdp.core.control.controller_spec import design_from_model
from hydro_sdp.core.control.loop_simulation import LoopJoint, run_closed_loop, valve_reversals
from hydro_sdp.core.errors import ConfigurationError
from hydro_sdp.core.identification.online import OnlineSdpIdentifier, OnlineSettings
from hydro_sdp.core.synthetic.programs import random_program
from hydro_sdp.io.model_files import default_model_path, load_model
from hydro_sdp.ros import bag_recorder
from hydro_sdp.ros.bag_player import BagPlayerNode
from hydro_sdp.ros.bag_recorder import BagRecorderNode
from hydro_sdp.ros.controller_node import PipControllerNode
from hydro_sdp.ros.identifier_node import IdentifierNode
from hydro_sdp.ros.plant_node import PlantNode
from hydro_sdp.ros.testing import Lockstep, RosHarness
import numpy as np
from outside import Processes
import pytest
from rclpy.parameter import Parameter
from sensor_msgs.msg import JointState
from std_msgs.msg import Bool, Float64

pytestmark = pytest.mark.ros


@pytest.fixture
def ros():
    """Return a harness with its own context, closed after the test."""
    with RosHarness() as harness:
        yield harness


def _collector(ros, topic, msgtype=JointState):
    helper = ros.helper(f'collect_{topic.replace("/", "_")}')
    received = []
    helper.create_subscription(msgtype, topic, received.append, 100)
    return helper, received


def _setpoint_publisher(ros, controller):
    helper = ros.helper('setpoints')
    publisher = helper.create_publisher(Float64, 'j2/setpoint', 10)
    assert ros.spin_until(lambda: publisher.get_subscription_count() >= 1)

    def send(degrees):
        count = controller.setpoints_received
        publisher.publish(Float64(data=math.radians(degrees)))
        assert ros.spin_until(lambda: controller.setpoints_received > count)
    return send


def test_lockstep_loop_reproduces_the_offline_closed_loop(ros):
    steps = 600
    plant = ros.add(PlantNode, parameters={'noise_std': 0.02, 'seed': 7})
    controller = ros.add(PipControllerNode)
    identifier = ros.add(IdentifierNode)
    _, states = _collector(ros, 'joint_states')
    loop = Lockstep(ros, plant, controllers=[controller], observers=[identifier])
    send = _setpoint_publisher(ros, controller)
    send(20.0)
    loop.run(steps)
    assert ros.spin_until(lambda: len(states) >= steps)
    measured = np.degrees([state.position[0] for state in states[:steps]])
    model = load_model(default_model_path())
    trace = run_closed_loop([LoopJoint(model, design_from_model(model).controller(),
                                       np.full(steps, 20.0), 0.0)],
                            dt=0.01, control_period=0.05, noise_std=0.02, seed=7)[0]
    np.testing.assert_allclose(measured, trace.measured, atol=1e-9, rtol=0)
    assert controller.outputs == steps // 5 and identifier.samples == steps


def _state(stamp_ns, names=('j2',), positions=(0.0,)):
    message = JointState()
    message.header.stamp.sec, message.header.stamp.nanosec = divmod(stamp_ns, 10**9)
    message.name = list(names)
    message.position = [float(p) for p in positions]
    return message


@pytest.mark.parametrize(('message', 'reason'), [
    (_state(10**8, positions=(math.nan,)), 'not finite'),
    (_state(10**8, positions=(math.inf,)), 'not finite'),
    (_state(10**8, names=('elbow',)), "joint 'j2' is not in JointState"),
    (_state(10**8, names=('j2', 'elbow'), positions=(0.1,)), '2 names but 1 positions'),
    (_state(10**8, names=(), positions=()), "joint 'j2' is not in JointState"),
    (_state(10**10), 's ahead of the node clock'),
])
def test_controller_refuses_bad_feedback_and_closes_the_valve(ros, message, reason):
    controller = ros.add(PipControllerNode)
    ros.set_time(10**8)
    _, commands = _collector(ros, 'j2/valve_command', Float64)
    send = _setpoint_publisher(ros, controller)
    send(20.0)
    controller._on_state(_state(5 * 10**7, positions=(0.0,)))
    assert controller.last_command > 1.0          # driving towards 20 deg
    controller._on_state(message)
    assert controller.refused == 1
    assert controller.last_command == 0.0         # valve closed
    assert ros.spin_until(lambda: len(commands) == 2 and commands[-1].data == 0.0)
    # The next valid sample resumes without a bump: from rest, not from the old command.
    controller._on_state(_state(2 * 10**8, positions=(0.0,)))
    assert 0.0 < controller.controller.last_u < 0.25


def test_duplicated_and_overtaken_samples_are_ignored_without_closing_the_valve(ros):
    controller = ros.add(PipControllerNode)
    ros.set_time(10**8)
    _setpoint_publisher(ros, controller)(20.0)
    controller._on_state(_state(5 * 10**7))
    driving = controller.last_command
    assert driving > 1.0
    controller._on_state(_state(5 * 10**7))           # duplicate
    controller._on_state(_state(10**6))               # overtaken by a newer sample
    assert controller.refused == 2 and controller.last_command == driving


def test_stale_feedback_is_refused_against_the_node_clock(ros):
    controller = ros.add(PipControllerNode)
    ros.set_time(5 * 10**9)
    controller._on_state(_state(5 * 10**9 - 10**7))
    assert controller.refused == 0 and controller.outputs == 1
    controller._on_state(_state(5 * 10**9 + 10**7))
    # A sample delayed by a 2 s burst arrives after fresher ones would have: refused.
    ros.set_time(8 * 10**9)
    controller._on_state(_state(6 * 10**9))
    assert controller.refused == 1 and controller.last_command == 0.0


def test_setpoints_beyond_the_end_stops_are_clamped_and_nan_is_refused(ros):
    controller = ros.add(PipControllerNode)
    send = _setpoint_publisher(ros, controller)
    send(90.0)
    assert controller.loops[0].setpoint == pytest.approx(63.6 - 0.5)   # setpoint_margin
    controller._on_setpoint(Float64(data=math.nan))
    assert controller.loops[0].setpoint == pytest.approx(63.6 - 0.5)   # setpoint_margin


def test_watchdog_closes_the_valve_and_control_resumes_without_a_bump(ros):
    steps = 60          # 0.6 s into a 30 deg step: the valve is wide open
    plant = ros.add(PlantNode)
    controller = ros.add(PipControllerNode, parameters={'feedback_timeout': 0.2})
    loop = Lockstep(ros, plant, controllers=[controller])
    send = _setpoint_publisher(ros, controller)
    send(30.0)
    loop.run(steps)
    assert controller.last_command > 1.0
    # The plant falls silent: time goes on, no feedback arrives.
    ros.executor.remove_node(plant)
    for k in range(1, 41):
        ros.set_time((steps + k) * 10**7)
        ros.spin_for(0.002)
    assert controller.gate.blind and controller.last_command == 0.0
    ros.executor.add_node(plant)
    before = plant.commands_received
    loop.steps = plant.ticks
    loop.run(5)
    assert not controller.gate.blind
    assert plant.commands_received > before
    assert abs(controller.controller.last_u) < 0.3    # restarted from rest, no jump


def test_a_pause_of_the_test_between_steps_is_no_silence_in_the_harness(ros):
    # The harness is the only clock: a test that computes between steps, or a busy host,
    # longer than feedback_timeout must not close the valve there (the loop stays the one
    # an offline run gives).
    plant = ros.add(PlantNode)
    controller = ros.add(PipControllerNode, parameters={'feedback_timeout': 0.2})
    loop = Lockstep(ros, plant, controllers=[controller])
    _setpoint_publisher(ros, controller)(30.0)
    loop.run(30)
    assert controller.last_command > 1.0
    ros.executor.remove_node(plant)          # no sample comes in between
    time.sleep(0.3)
    ros.set_time(ros.time_ns + 10**8)        # the watchdog's instant, half the timeout on
    ros.spin_for(0.05)
    assert not controller.gate.blind and controller.last_command > 1.0


def test_idz_parameters_change_at_run_time_and_are_validated(ros):
    controller = ros.add(PipControllerNode)
    result = controller.set_parameters([Parameter('idz.dead_zone', value=[-1.2, 1.1])])
    assert result[0].successful
    assert controller.controller.settings.idz.dead_zone == (-1.2, 1.1)
    result = controller.set_parameters([Parameter('idz.dead_zone', value=[1.2, -1.1])])
    assert not result[0].successful and 'reversed' in result[0].reason
    result = controller.set_parameters([Parameter('idz.slopes', value=[0.0, 1.0])])
    assert not result[0].successful and 'slopes' in result[0].reason
    result = controller.set_parameters([Parameter('idz.beta', value=500.0)])
    assert not result[0].successful
    result = controller.set_parameters([Parameter('gains.k_i', value=5.0)])
    assert not result[0].successful and 'unstable' in result[0].reason
    assert controller.controller.settings.idz.dead_zone == (-1.2, 1.1)


#: Set-points of 4 s: three before the wear, five after it (from the first hold after the
#: wear each hunts alike, by 2-3 deg with ten valve reversals; the last four are judged).
HOLDS = 8


def test_without_recalibration_the_worn_valve_makes_the_loop_hunt(ros):
    # Set-point steps (4 s each) while the plant's dead-zone narrows by 0.3 V at 12 s, the
    # scenario of test_identifier_node's wear tests, where the identifier recalibrates.
    plant = ros.add(PlantNode, parameters={'noise_std': 0.01, 'seed': 2})
    controller = ros.add(PipControllerNode)
    loop = Lockstep(ros, plant, controllers=[controller])
    send = _setpoint_publisher(ros, controller)
    levels = [20.0, 35.0, 15.0, 30.0]
    errors, commands = [], []
    for hold in range(HOLDS):
        if hold == 3:
            assert plant.set_parameters([Parameter('dead_zone_shift',
                                                   value=[0.3, -0.3])])[0].successful
        target = levels[hold % len(levels)]
        send(target)
        for _ in range(400):
            loop.step()
            errors.append(plant.last_angles[0] - target)
            commands.append(controller.last_command)
    settled = np.abs(np.array(errors).reshape(HOLDS, 400)[:, -50:]).max(axis=1)
    # Before the wear every hold settles; after it the IDZ over-compensates: a limit cycle.
    assert settled[:3].max() < 0.5
    assert settled[-4:].max() > 0.5 and valve_reversals(np.array(commands[-1600:])) > 20


def test_replayed_bag_feeds_the_identifier_as_identify_reads_it(ros, tmp_path):
    steps = 1000
    shift = [0.2, -0.15]
    plant = ros.add(PlantNode, parameters={'noise_std': 0.03, 'seed': 3,
                                           'initial_angles': [25.0]})
    assert plant.set_parameters([Parameter('dead_zone_shift', value=shift)])[0].successful
    recorder = ros.add(BagRecorderNode, parameters={'output': str(tmp_path / 'bag')})
    _, published = _collector(ros, 'joint_states')
    helper = ros.helper('commands')
    publisher = helper.create_publisher(Float64, 'j2/valve_command', 10)
    assert ros.spin_until(lambda: publisher.get_subscription_count() >= 2)
    model = load_model(default_model_path())
    program = random_program(model, 0.01, steps * 0.01, seed=4, y0=25.0)
    loop = Lockstep(ros, plant, observers=[])
    for k in range(steps):
        # Each command half a period after a sample, as a controller's would be: the
        # recorder's stamps (its clock at receipt) then order every message as it happened.
        ros.set_time(k * 10_000_000 + 5_000_000)
        publisher.publish(Float64(data=float(program[k])))
        assert ros.spin_until(lambda: plant.commands_received == k + 1 and
                              recorder.messages == 2 * k + 1)
        loop.step()
        assert ros.spin_until(lambda: recorder.messages == 2 * k + 2)
    recorder.close()
    assert ros.spin_until(lambda: len(published) == steps)
    angles = np.degrees([message.position[0] for message in published])
    record = read_bag(tmp_path / 'bag').record()
    assert record.v.size == steps
    player = ros.add(BagPlayerNode, parameters={'bag': str(tmp_path / 'bag'),
                                                'autostart': False})
    identifier = ros.add(IdentifierNode, parameters={'noise_std': 0.03})
    assert ros.spin_until(lambda: player.count_subscribers('joint_states') >= 1)
    while not player.finished:
        # One message at a time, consumed before the next: the identifier pairs each angle
        # with the command received before it, as the bag reader does.
        before = (identifier.samples, identifier.commands_received)
        player.play_next()
        assert ros.spin_until(lambda: (identifier.samples, identifier.commands_received) !=
                              before)
    # The same filter fed the pairs read_bag gives ends where the node's did: the node saw
    # exactly those pairs (the filter is deterministic).
    offline = OnlineSdpIdentifier(model, 0.01, OnlineSettings.for_input_limits(
        model.input_limits, noise_std=0.03))
    for v, y in zip(record.v.tolist(), record.y.tolist()):
        offline.update(v, y)
    assert offline.samples == identifier.estimator.samples == record.v.size
    np.testing.assert_allclose(identifier.estimator.theta, offline.theta, rtol=0, atol=1e-12)
    # And what identify reads is what was sent and what the plant published, sample for
    # sample: the command in force over each interval, the angle at its end.
    np.testing.assert_array_equal(record.v, program[:steps])
    np.testing.assert_allclose(record.y, angles, rtol=0, atol=1e-12)


def test_on_simulated_time_a_late_callback_keeps_the_clock_stamp(ros, tmp_path, monkeypatch):
    # The wall-clock lateness of a callback is undone only where the clock runs with the
    # wall: on simulated time the clock stood still meanwhile (a command stamped 5 ms
    # early would land before the sample it follows).
    recorder = ros.add(BagRecorderNode, parameters={'output': str(tmp_path / 'bag'),
                                                    'topics': ['j2/valve_command']})
    publisher = ros.helper('late').create_publisher(Float64, 'j2/valve_command', 10)
    assert ros.spin_until(lambda: publisher.get_subscription_count() >= 1)
    wall = time.time_ns
    monkeypatch.setattr(bag_recorder.time, 'time_ns', lambda: wall() + 5_000_000)
    ros.set_time(7_005_000_000)
    publisher.publish(Float64(data=1.5))
    assert ros.spin_until(lambda: recorder.messages == 1)
    recorder.close()
    with sqlite3.connect(next((tmp_path / 'bag').glob('*.db3'))) as database:
        assert database.execute('SELECT timestamp FROM messages').fetchall() == [
            (7_005_000_000,)]


def test_recorder_and_player_refuse_missing_settings(ros):
    with pytest.raises(ConfigurationError, match="'output'"):
        ros.add(BagRecorderNode)
    with pytest.raises(ConfigurationError, match="'bag'"):
        ros.add(BagPlayerNode)


@pytest.mark.slow
def test_nodes_as_separate_processes_settle_a_step(tmp_path, monkeypatch):
    machine = Processes(monkeypatch, ('plant_node', ['-p', 'noise_std:=0.01']),
                        ('controller_node', []), ('identifier_node', []))
    executor = machine.executor
    angles = []
    machine.node.create_subscription(JointState, 'joint_states',
                                     lambda m: angles.append((time.monotonic(),
                                                              math.degrees(m.position[0]))),
                                     100)
    publisher = machine.node.create_publisher(Float64, 'j2/setpoint', 10)
    try:
        deadline = time.monotonic() + 30.0
        while (publisher.get_subscription_count() < 1 or len(angles) < 10) and \
                time.monotonic() < deadline:
            executor.spin_once(timeout_sec=0.05)
        assert angles, 'no joint_states from the plant process'
        start = time.monotonic()
        publisher.publish(Float64(data=math.radians(20.0)))
        while time.monotonic() < start + 8.0:
            executor.spin_once(timeout_sec=0.05)
        after = [(t - start, a) for t, a in angles if t >= start]
        settled = [a for t, a in after if t >= 6.0]
        assert settled and max(abs(a - 20.0) for a in settled) < 0.5
    finally:
        machine.close()


def test_plant_simulates_several_joints_in_one_joint_state(ros):
    files = [str(REPO / 'config' / name) for name in ('lucie_boom.yaml', 'lucie_dipper.yaml')]
    plant = ros.add(PlantNode, parameters={'model_files': files, 'sample_period': 0.02,
                                           'initial_angles': [5.0, -80.0]})
    _, states = _collector(ros, 'joint_states')
    helper = ros.helper('dipper_command')
    publisher = helper.create_publisher(Float64, 'dipper/valve_command', 10)
    loop = Lockstep(ros, plant)
    assert ros.spin_until(lambda: publisher.get_subscription_count() >= 1)
    publisher.publish(Float64(data=300.0))
    assert ros.spin_until(lambda: plant.commands_received == 1)
    loop.run(50)
    assert ros.spin_until(lambda: len(states) >= 50)
    assert list(states[-1].name) == ['boom', 'dipper']
    boom, dipper = np.degrees(states[-1].position)
    assert boom == pytest.approx(5.0)                      # no command: at rest
    assert dipper > -80.0 + 10.0                           # driven for about 1 s


def test_identifier_publishes_estimates_and_the_recalibration_flag(ros):
    plant = ros.add(PlantNode, parameters={'noise_std': 0.01})
    controller = ros.add(PipControllerNode)
    identifier = ros.add(IdentifierNode, parameters={'noise_std': 0.01})
    helper, lower = _collector(ros, 'j2/sdp/dead_zone_lower', Float64)
    flags = []
    helper.create_subscription(Bool, 'j2/sdp/recalibration_needed', flags.append, 100)
    loop = Lockstep(ros, plant, controllers=[controller], observers=[identifier])
    send = _setpoint_publisher(ros, controller)
    send(30.0)
    loop.run(300)
    assert ros.spin_until(lambda: len(lower) >= 25 and len(flags) >= 25)
    assert lower[-1].data == pytest.approx(-1.3298, abs=0.05)
    assert flags[-1].data is False          # the model is right: nothing to recalibrate

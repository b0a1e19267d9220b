"""One controller node for boom and dipper: per-joint topics and parameters, trajectories."""

import math

from conftest import REPO
from hydro_sdp.core.control.controller_spec import design_from_model
from hydro_sdp.core.control.loop_simulation import LoopJoint, run_closed_loop
from hydro_sdp.core.control.trajectory import JointTrajectory, TrajectorySampler
from hydro_sdp.io.model_files import load_model
from hydro_sdp.ros.controller_node import PipControllerNode
from hydro_sdp.ros.conversions import CONTROLLER_STATE_LABELS
from hydro_sdp.ros.plant_node import PlantNode
from hydro_sdp.ros.testing import Lockstep, RosHarness
import numpy as np
import pytest
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64, Float64MultiArray
from trajectory_msgs.msg import JointTrajectory as TrajectoryMessage

pytestmark = pytest.mark.ros

MODELS = [str(REPO / 'config' / 'lucie_boom.yaml'), str(REPO / 'config' / 'lucie_dipper.yaml')]
JOINTS = ['boom', 'dipper']
START = {'boom': 0.0, 'dipper': -90.0}      # where the plant starts them (mid-travel dipper)
# A ramp of 5 deg/s for 4 s on both joints, then a hold.
TIMES = [4.0]
ENDS = [[20.0, -70.0]]


@pytest.fixture
def ros():
    """Return a harness with its own context, closed after the test."""
    with RosHarness() as harness:
        yield harness


def _arm(ros, **parameters):
    plant = ros.add(PlantNode, parameters={'model_files': MODELS})
    controller = ros.add(PipControllerNode, parameters={
        'joints': JOINTS, 'model_files': MODELS, **parameters})
    return plant, controller


def _collect(ros, topic, msgtype):
    received = []
    ros.helper(f'collect_{topic.replace("/", "_")}').create_subscription(
        msgtype, topic, received.append, 100)
    return received


def test_one_node_commands_each_joint_and_declares_its_parameters(ros):
    plant, controller = _arm(ros)
    assert controller.joints == JOINTS and controller.state_label() == 'active'
    for joint in JOINTS:
        assert controller.count_publishers(f'{joint}/valve_command') == 1
        assert controller.count_subscribers(f'{joint}/setpoint') == 1
        assert controller.get_parameter(f'{joint}.gains.k_i').value == \
            controller.loop(joint).spec.gains.k_i
    # Several joints: only the per-joint names.
    assert not controller.has_parameter('gains.k_i')
    edges = controller.loop('dipper').spec.idz.dead_zone
    result = controller.set_parameters_atomically([
        _parameter('dipper.idz.dead_zone', [edges[0] - 5.0, edges[1] + 5.0])])
    assert result.successful
    assert controller.loop('dipper').spec.idz.dead_zone == (edges[0] - 5.0, edges[1] + 5.0)
    assert controller.loop('boom').spec.idz.dead_zone != (edges[0] - 5.0, edges[1] + 5.0)
    # An unstable gain of one joint refuses the whole request.
    before = controller.loop('boom').spec
    result = controller.set_parameters_atomically([
        _parameter('boom.gains.k_i', 5.0), _parameter('dipper.idz.beta', 0.0)])
    assert not result.successful and 'unstable' in result.reason
    assert controller.loop('boom').spec == before


def _parameter(name, value):
    from rclpy.parameter import Parameter
    return Parameter(name, value=value)


def _offline(start, steps, period=0.01):
    """Run the offline closed loop of both joints following the ramp from ``start`` (s)."""
    sampler = TrajectorySampler(START)
    sampler.replace(JointTrajectory(tuple(JOINTS), np.array(TIMES), np.array(ENDS)), start)
    t = np.arange(steps) * period
    loop = []
    for path in MODELS:
        model = load_model(path)
        spec = design_from_model(model)
        ahead = np.array([sampler.feedforward(model.joint, float(x), spec.control_period,
                                              spec.delay_samples) for x in t])
        loop.append(LoopJoint(model, spec.controller(), sampler.setpoints(model.joint, t),
                              START[model.joint], ahead))
    return run_closed_loop(loop, dt=period, control_period=0.05, noise_std=0.0)


def test_a_trajectory_is_tracked_as_the_offline_loop_tracks_it(ros):
    plant, controller = _arm(ros)
    states = _collect(ros, 'joint_states', JointState)
    controller_states = _collect(ros, 'boom/controller_state', Float64MultiArray)
    publisher = ros.helper().create_publisher(TrajectoryMessage, 'joint_trajectory', 10)
    loop = Lockstep(ros, plant, controllers=[controller])
    loop.run(20)                                  # the joints hold where they are
    # Stamped to start at 1 s: the feed-forward looks ahead by the loop's delay.
    ros.send_trajectory(publisher, [controller], JOINTS, TIMES, ENDS, stamp_ns=10**9)
    assert controller.trajectories_refused == 0
    steps = 800
    loop.run(steps - 20)
    assert ros.spin_until(lambda: len(states) >= steps)
    measured = np.degrees([state.position for state in states[:steps]])
    # Sample j of the plant is stamped (j + 1) periods.
    traces = _offline(start=1.0 - 0.01, steps=steps)
    for column, trace in enumerate(traces):
        np.testing.assert_allclose(measured[:, column], trace.measured, atol=1e-9, rtol=0)
        moving = (trace.t >= 0.99) & (trace.t <= 4.99)
        error = trace.measured - trace.setpoint
        assert np.sqrt(np.mean(error[moving] ** 2)) < 1.5        # deg, RMS during the ramp
        assert abs(error[-1]) < 0.5                              # deg, final
    # The controller state of the last step: set-point, angle, error, u, v.
    assert ros.spin_until(lambda: len(controller_states) >= steps // 5 - 1)
    last = controller_states[-1]
    assert [d.label for d in last.layout.dim] == [','.join(CONTROLLER_STATE_LABELS)]
    setpoint, angle, error, _, v = last.data
    assert math.degrees(setpoint) == pytest.approx(20.0)
    assert error == pytest.approx(setpoint - angle)
    assert v == controller.loop('boom').last_command


def test_without_feedforward_the_ramp_lags(ros):
    plant, controller = _arm(ros, feedforward=False)
    publisher = ros.helper().create_publisher(TrajectoryMessage, 'joint_trajectory', 10)
    loop = Lockstep(ros, plant, controllers=[controller])
    loop.run(5)
    ros.send_trajectory(publisher, [controller], ['boom'], TIMES, [[20.0]])
    loop.run(300)                                   # 3 s into the 4 s ramp
    boom = controller.loop('boom')
    spec = boom.spec
    # The PIP alone lags a ramp of r deg per control sample by f0 r / kI (docs/methods.md 4.9).
    r = 5.0 * spec.control_period
    lag = spec.gains.f[0] * r / spec.gains.k_i
    assert boom.last_setpoint - boom.angle == pytest.approx(lag, rel=0.1)


def test_trajectories_naming_unknown_joints_or_beyond_the_stops_are_refused_whole(ros):
    plant, controller = _arm(ros)
    publisher = ros.helper().create_publisher(TrajectoryMessage, 'joint_trajectory', 10)
    loop = Lockstep(ros, plant, controllers=[controller])
    loop.run(5)
    ros.send_trajectory(publisher, [controller], ['boom', 'bucket'], [1.0], [[10.0, 0.0]])
    ros.send_trajectory(publisher, [controller], ['boom', 'dipper'], [1.0], [[10.0, -10.0]])
    assert controller.trajectories_refused == 2
    assert not any(loop_.following for loop_ in controller.loops)
    loop.run(100)
    for joint in JOINTS:
        assert controller.loop(joint).last_setpoint == pytest.approx(START[joint])


def test_a_new_trajectory_replaces_the_rest_and_a_setpoint_ends_it(ros):
    plant, controller = _arm(ros)
    publisher = ros.helper().create_publisher(TrajectoryMessage, 'joint_trajectory', 10)
    setpoint = ros.helper('setpoints').create_publisher(Float64, 'dipper/setpoint', 10)
    loop = Lockstep(ros, plant, controllers=[controller])
    loop.run(5)
    ros.send_trajectory(publisher, [controller], ['boom'], [2.0], [[20.0]])
    loop.run(100)                                   # 1 s: halfway, at 10 deg
    ros.send_trajectory(publisher, [controller], ['boom'], [1.0], [[0.0]])
    boom = controller.loop('boom')
    loop.run(50)                                    # back towards 0 from ~10 deg
    # From 10 deg at 1.05 s to 0 at 2.05 s: 5 deg at 1.55 s, within one control period (0.5 deg).
    assert boom.last_setpoint == pytest.approx(5.0, abs=0.5)
    loop.run(100)
    assert boom.last_setpoint == 0.0
    # The dipper never moved; a step set-point goes on working.
    count = controller.setpoints_received
    ros.send(setpoint, Float64(data=math.radians(-80.0)),
             lambda: controller.setpoints_received > count)
    loop.run(5)
    assert controller.loop('dipper').last_setpoint == pytest.approx(-80.0)


@pytest.mark.slow
def test_boom_and_dipper_processes_follow_a_ramp(monkeypatch, capsys):
    from hydro_sdp.ros.conversions import fill_trajectory
    from outside import ARM, CONTROLLER, Processes
    nodes = Processes(monkeypatch, ('plant_node', ARM), ('controller_node', CONTROLLER))
    try:
        client = nodes.node
        states, commands = [], []
        client.create_subscription(JointState, 'joint_states', states.append, 100)
        client.create_subscription(Float64, 'boom/valve_command', commands.append, 100)
        publisher = client.create_publisher(TrajectoryMessage, 'joint_trajectory', 10)
        assert nodes.spin_until(lambda: publisher.get_subscription_count() >= 1
                                and len(commands) > 5, 30.0), nodes.died()
        # Every process reads the system clock: start the ramp 1 s from now.
        start_ns = client.get_clock().now().nanoseconds + 10**9
        publisher.publish(fill_trajectory(TrajectoryMessage(), JOINTS, TIMES, ENDS, start_ns))
        start = start_ns * 1e-9
        nodes.spin_until(lambda: states and _stamp(states[-1]) > start + TIMES[-1] + 3.0, 20.0)
    finally:
        nodes.close()
    sampler = TrajectorySampler(START)
    sampler.replace(JointTrajectory(tuple(JOINTS), np.array(TIMES), np.array(ENDS)), start)
    stamps = np.array([_stamp(state) for state in states])
    measured = np.degrees([[state.position[state.name.index(j)] for j in JOINTS]
                           for state in states])
    moving = (stamps >= start) & (stamps <= start + TIMES[-1])
    # The client keeps what it takes in time (100-message queue): on a busy machine some of
    # the 400 samples of the ramp pass it by; half of them judge the tracking well enough.
    assert moving.sum() > 200 and stamps[-1] > start + TIMES[-1] + 2.5
    with capsys.disabled():
        print()
    for column, joint in enumerate(JOINTS):
        error = measured[:, column] - sampler.setpoints(joint, stamps)
        rms = float(np.sqrt(np.mean(error[moving] ** 2)))
        final = float(abs(error[-1]))
        with capsys.disabled():
            print(f'{joint}: RMS tracking error during the ramp {rms:.3f} deg, final error '
                  f'{final:.3f} deg')
        assert rms < 1.5 and final < 0.5


def _stamp(state):
    return state.header.stamp.sec + state.header.stamp.nanosec * 1e-9


class _ShiftedEstimator:
    """Stands in for the online filter of a joint whose dead-zone moved: a set estimate."""

    delay = 10

    def __init__(self, model, edges, std=1.0):
        from hydro_sdp.core.identification.online import SdpEstimate
        static = model.static_map
        self.model = model
        self.named = SdpEstimate(edges[0], edges[1], *static.saturation_velocity,
                                 *static.curvature, std, std, 0.5, 0.5, 1e-4, 1e-4)

    def update(self, v, y):
        return True

    def named_estimate(self):
        return self.named

    def estimate(self):
        from dataclasses import replace
        from hydro_sdp.core.model.static_maps import SdpMap
        static = self.model.static_map
        return replace(self.model, static_map=SdpMap(
            dead_zone=self.named.edges, saturation_velocity=static.saturation_velocity,
            curvature=static.curvature))


def test_one_identifier_recalibrates_each_joint_of_one_controller(ros):
    from hydro_sdp.ros.identifier_node import IdentifierNode
    plant, controller = _arm(ros)
    identifier = ros.add(IdentifierNode, parameters={
        'joints': JOINTS, 'model_files': MODELS, 'auto_recalibrate': True, 'settle': 0.5})
    assert [item.joint for item in identifier.identified] == JOINTS
    dipper = identifier.item('dipper')
    assert dipper.recalibration.reference == (-60.0, 55.0)
    worn = (-40.0, 35.0)
    dipper.estimator = _ShiftedEstimator(dipper.model, worn)
    boom_edges = controller.loop('boom').spec.idz.dead_zone
    loop = Lockstep(ros, plant, controllers=[controller], observers=[identifier])
    loop.run(200)
    assert ros.spin_until(lambda: dipper.recalibrations == 1)
    assert controller.loop('dipper').spec.idz.dead_zone == worn
    assert controller.get_parameter('dipper.idz.dead_zone').value.tolist() == list(worn)
    assert controller.loop('boom').spec.idz.dead_zone == boom_edges
    assert identifier.item('boom').recalibrations == 0


def test_trajectory_messages_are_read_in_degrees_with_their_velocities():
    from hydro_sdp.core.errors import DataError
    from hydro_sdp.ros.conversions import fill_trajectory, trajectory_from_message
    from trajectory_msgs.msg import JointTrajectoryPoint
    message = fill_trajectory(TrajectoryMessage(), JOINTS, [0.5, 2.25], [[10.0, -80.0],
                                                                         [20.0, -70.0]],
                              stamp_ns=3 * 10**9 + 5)
    trajectory, stamp = trajectory_from_message(message)
    assert stamp == pytest.approx(3.000000005)
    assert trajectory.joint_names == tuple(JOINTS) and trajectory.velocities is None
    np.testing.assert_allclose(trajectory.times, [0.5, 2.25])
    np.testing.assert_allclose(trajectory.positions, [[10.0, -80.0], [20.0, -70.0]])
    for point in message.points:
        point.velocities = [math.radians(5.0), 0.0]
    trajectory, _ = trajectory_from_message(message)
    np.testing.assert_allclose(trajectory.velocities, [[5.0, 0.0], [5.0, 0.0]])
    message.points.append(JointTrajectoryPoint(positions=[0.0]))
    with pytest.raises(DataError, match=r'points \[2\] do not have one position per joint'):
        trajectory_from_message(message)
    message.points = []
    with pytest.raises(DataError, match='no points'):
        trajectory_from_message(message)


def test_one_joint_keeps_its_plain_parameter_names_in_step_with_its_own(ros):
    controller = ros.add(PipControllerNode)
    k_i = controller.spec.gains.k_i
    assert controller.get_parameter('j2.gains.k_i').value == k_i
    assert controller.set_parameters([_parameter('j2.gains.k_i', 0.9 * k_i)])[0].successful
    assert controller.get_parameter('gains.k_i').value == pytest.approx(0.9 * k_i)
    assert controller.set_parameters([_parameter('idz.beta', 0.25)])[0].successful
    assert controller.get_parameter('j2.idz.beta').value == 0.25
    assert controller.spec.gains.k_i == pytest.approx(0.9 * k_i)
    assert controller.spec.idz.beta == 0.25

"""
The controller node's parameters: checked as a whole, applied at run time, integers for doubles.

In-process with the harness, over the node's parameter services as ``ros2 param set`` calls
them (:class:`~hydro_sdp.ros.testing.ParameterClient`: values travel as messages, an integer
stays an integer), and with the command-line arguments ``ros2 run`` passes.
"""

from dataclasses import replace
import math

from hydro_sdp.core.control.controller_spec import design_from_model
from hydro_sdp.core.control.idz_table import TableInverseDeadZone
from hydro_sdp.core.control.pip_controller import PipIdzController
from hydro_sdp.core.errors import ConfigurationError
from hydro_sdp.core.model.joint_model import JointModel
from hydro_sdp.core.model.static_maps import PowerSatMap
from hydro_sdp.io.controller_files import save_controller
from hydro_sdp.io.model_files import default_model_path, load_model, save_model
from hydro_sdp.ros.controller_node import PipControllerNode
from hydro_sdp.ros.testing import ParameterClient, RosHarness
import pytest
from rclpy.parameter import Parameter
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64

pytestmark = pytest.mark.ros

NEW_EDGES = [-1.0, 1.0]


@pytest.fixture
def ros():
    """Return a harness with its own context, closed after the test."""
    with RosHarness() as harness:
        yield harness


def _state(stamp_ns, angle_deg=0.0):
    message = JointState()
    message.header.stamp.sec, message.header.stamp.nanosec = divmod(stamp_ns, 10**9)
    message.name, message.position = ['j2'], [math.radians(angle_deg)]
    return message


def _first_command(setpoint, angle=0.0, edges=None):
    """Return the command a fresh default controller answers to one sample."""
    spec = design_from_model(load_model(default_model_path()))
    settings = spec.settings()
    if edges is not None:
        settings = replace(settings, idz=replace(spec.idz, dead_zone=tuple(edges)))
    return PipIdzController(settings).step(setpoint, angle)[1]


def test_a_refused_atomic_change_changes_nothing(ros):
    controller = ros.add(PipControllerNode)
    client = ParameterClient(ros, 'pip_controller')
    before = (controller.spec, controller.controller.settings)
    result = client.set_atomically(idz__dead_zone=NEW_EDGES, gains__k_i=5.0)
    assert not result.successful and 'unstable' in result.reason
    assert (controller.spec, controller.controller.settings) == before
    (_, edges), (_, k_i) = client.get('idz.dead_zone', 'gains.k_i')
    assert list(edges) == [-1.3298, 1.3124] and k_i == before[0].gains.k_i
    ros.set_time(10**8)
    controller._on_setpoint(Float64(data=math.radians(20.0)))
    controller._on_state(_state(10**8))
    # The first answer is the unchanged controller's, to the last digit.
    assert controller.last_command == pytest.approx(_first_command(20.0), abs=1e-12)
    # The IDZ alone is accepted and applies to the next step from rest (after the watchdog
    # closed the valve: 0.6 s without feedback).
    assert client.set_atomically(idz__dead_zone=NEW_EDGES).successful
    ros.set_time(7 * 10**8)
    assert ros.spin_until(lambda: controller.gate.blind) and controller.last_command == 0.0
    controller._on_state(_state(7 * 10**8))
    assert controller.last_command == pytest.approx(_first_command(20.0, edges=NEW_EDGES),
                                                    abs=1e-12)


def test_an_accepted_change_keeps_the_spec_current(ros):
    controller = ros.add(PipControllerNode)
    gains, design = controller.spec.gains, controller.spec.design
    assert controller.set_parameters_atomically([
        Parameter('idz.dead_zone', value=NEW_EDGES), Parameter('idz.beta', value=0.1),
        Parameter('gains.k_i', value=gains.k_i * 0.5)]).successful
    assert controller.spec.idz.dead_zone == (-1.0, 1.0) and controller.spec.idz.beta == 0.1
    assert controller.spec.gains == replace(gains, k_i=gains.k_i * 0.5)
    assert controller.controller.settings == controller.spec.settings()
    # A later gain change keeps the IDZ set before (the spec is not rebuilt from stale parts).
    assert controller.set_parameters([Parameter('gains.k_i', value=gains.k_i)])[0].successful
    assert controller.spec.idz.dead_zone == (-1.0, 1.0)
    assert controller.controller.settings.idz.dead_zone == (-1.0, 1.0)
    # How the gains were designed is what the node started with, not rebuilt from the model.
    assert controller.spec.design == design and design['method'] == 'lq'


def test_integers_are_accepted_for_double_parameters():
    # At start-up from the command line (as ros2 run passes -p), and at run time over the
    # services (as ros2 param set sends them).
    with RosHarness(args=['--ros-args', '-p', 'feedback_timeout:=1',
                          '-p', 'setpoint_margin:=2']) as ros:
        controller = ros.add(PipControllerNode)
        client = ParameterClient(ros, 'pip_controller')
        assert client.get('feedback_timeout') == [(Parameter.Type.DOUBLE, 1.0)]
        assert controller.gate.timeout_ns == 10**9 and controller.setpoint_margin == 2.0
        result = client.set_each(idz__beta=0, idz__dead_zone=[-1, 1], gains__k_i=1)
        assert result[0].successful and controller.spec.idz.beta == 0.0
        assert result[1].successful and controller.spec.idz.dead_zone == (-1.0, 1.0)
        assert client.get('idz.dead_zone')[0][0] == Parameter.Type.DOUBLE_ARRAY
        # kI = 1 arrives as a double and is then refused for what it does, not for its type.
        assert not result[2].successful and 'unstable' in result[2].reason
        result = client.set_each(idz__beta=500)
        assert not result[0].successful and 'out of range' in result[0].reason


def test_feedback_timeout_applies_at_run_time(ros):
    controller = ros.add(PipControllerNode)
    client = ParameterClient(ros, 'pip_controller')
    assert controller.interfaces.watchdog.timer_period_ns == 10**8
    assert client.set_atomically(feedback_timeout=2).successful          # an integer
    assert controller.gate.timeout_ns == 2 * 10**9
    ros.set_time(10**8)
    controller._on_setpoint(Float64(data=math.radians(20.0)))
    controller._on_state(_state(10**8))
    assert controller.last_command > 1.0
    for k in range(2, 21):                      # 1.9 s of silence: still inside the timeout
        ros.set_time(k * 10**8)
        ros.spin_for(0.002)
    assert not controller.gate.blind and controller.last_command > 1.0
    # A stamp 1.5 s old is fresh enough for a 2 s timeout.
    controller._on_state(_state(5 * 10**8))
    assert controller.refused == 0
    assert client.set_atomically(feedback_timeout=0.06).successful
    assert controller.interfaces.watchdog.timer_period_ns == 3 * 10**7
    ros.set_time(21 * 10**8)
    ros.spin_for(0.01)
    assert controller.gate.blind and controller.last_command == 0.0


def test_setpoint_margin_applies_at_run_time(ros):
    controller = ros.add(PipControllerNode)
    controller._on_setpoint(Float64(data=math.radians(90.0)))
    assert controller.loops[0].setpoint == pytest.approx(63.1)
    assert controller.set_parameters([Parameter('setpoint_margin', value=5.0)])[0].successful
    assert controller.loops[0].setpoint == pytest.approx(58.6)          # the held set-point too
    controller._on_setpoint(Float64(data=math.radians(-40.0)))
    assert controller.loops[0].setpoint == pytest.approx(-8.8)
    result = controller.set_parameters([Parameter('setpoint_margin', value=40.0)])
    assert not result[0].successful and 'leaves no set-point' in result[0].reason
    assert controller.setpoint_margin == 5.0


def test_read_only_parameters_refuse_changes(ros):
    ros.add(PipControllerNode)
    client = ParameterClient(ros, 'pip_controller')
    for name, value in (('joint', 'j3'), ('control_period', 0.1), ('model_file', 'x.yaml'),
                        ('controller_file', 'c.yaml')):
        result = client.set_atomically(**{name: value})
        assert not result.successful and 'read-only' in result.reason


def test_a_controller_file_for_another_valve_range_is_refused(ros, tmp_path):
    model = load_model(default_model_path())
    percent = replace(model, input_limits=(-100.0, 100.0))
    save_controller(design_from_model(percent), tmp_path / 'c.yaml')
    with pytest.raises(ConfigurationError,
                       match=r'controller commands the valve over \[-100.0, 100.0\], beyond '
                             r'the range \[-10.0, 10.0\].*hydro-sdp design'):
        ros.add(PipControllerNode, parameters={'controller_file': str(tmp_path / 'c.yaml')})
    other = tmp_path / 'boom.yaml'
    other.write_text(default_model_path().read_text().replace('joint: j2', 'joint: boom'))
    save_controller(design_from_model(load_model(other)), tmp_path / 'boom_c.yaml')
    with pytest.raises(ConfigurationError, match="controller is for joint 'boom'"):
        ros.add(PipControllerNode,
                parameters={'controller_file': str(tmp_path / 'boom_c.yaml')})


#: A convex valve in signed percent (a power_sat map as identify fits to an arm's logs).
ARM = JointModel('arm', PowerSatMap((-31.5, 16.0), (-47.4, 32.3), (0.0206, 0.0195), (2.2, 4.5)),
                 0.39, angle_limits=(-45.0, 40.0), input_limits=(-100.0, 100.0))


def test_idz_parameters_move_and_scale_a_table(ros, tmp_path):
    # Design writes a table for this map, and the node loads it.
    model = ARM
    save_model(model, tmp_path / 'arm.yaml')
    spec = design_from_model(model)
    save_controller(spec, tmp_path / 'arm_controller.yaml')
    controller = ros.add(PipControllerNode, parameters={
        'model_file': str(tmp_path / 'arm.yaml'),
        'controller_file': str(tmp_path / 'arm_controller.yaml')})
    table = controller.controller.settings.idz
    assert isinstance(table, TableInverseDeadZone) and table == spec.idz
    assert controller.get_parameter('idz.dead_zone').value == pytest.approx([-31.5, 16.0])
    # A recalibrated edge shifts that side of the table; the other side stays.
    result = controller.set_parameters([Parameter('arm.idz.dead_zone', value=[-31.5, 20.0])])
    assert result[0].successful, result[0].reason
    moved = controller.controller.settings.idz
    assert moved.dead_zone == pytest.approx((-31.5, 20.0))
    assert moved.command(0.5)[0] == pytest.approx(table.command(0.5)[0] + 4.0)
    assert moved.command(-0.5)[0] == pytest.approx(table.command(-0.5)[0])
    assert controller.get_parameter('idz.dead_zone').value == pytest.approx([-31.5, 20.0])
    # New slopes scale a branch's increments; beta and mode apply as they are.
    slopes = list(moved.slopes)
    result = controller.set_parameters([
        Parameter('idz.slopes', value=[slopes[0], 2.0 * slopes[1]]),
        Parameter('idz.beta', value=0.03), Parameter('idz.mode', value='hysteresis')])
    assert all(r.successful for r in result)
    scaled = controller.controller.settings.idz
    assert scaled.slopes == pytest.approx((slopes[0], 2.0 * slopes[1]))
    assert scaled.u_range[1] == pytest.approx(2.0 * moved.u_range[1])
    assert (scaled.beta, scaled.mode) == (0.03, 'hysteresis')
    result = controller.set_parameters([Parameter('idz.dead_zone', value=[5.0, 20.0])])
    assert not result[0].successful and 'rest' in result[0].reason
    result = controller.set_parameters([Parameter('idz.slopes', value=[0.0, 1.0])])
    assert not result[0].successful and 'slopes' in result[0].reason
    assert controller.controller.settings.idz == scaled
    # The fade-in band (methods.md 5.2) works with the zero mode only, and takes effect.
    result = controller.set_parameters([Parameter('idz.fade', value=0.06)])
    assert not result[0].successful and 'mode zero, not hysteresis' in result[0].reason
    assert controller.controller.settings.idz == scaled
    result = controller.set_parameters_atomically([
        Parameter('idz.mode', value='zero'), Parameter('arm.idz.fade', value=0.06)])
    assert result.successful, result.reason
    faded = controller.controller.settings.idz
    assert (faded.fade, faded.mode) == (0.06, 'zero') and faded.command(0.03)[0] == 0.0
    assert controller.get_parameter('idz.fade').value == 0.06


def test_a_power_sat_model_alone_gets_a_table(ros, tmp_path):
    save_model(ARM, tmp_path / 'arm.yaml')
    controller = ros.add(PipControllerNode, parameters={'model_file': str(tmp_path / 'arm.yaml')})
    assert isinstance(controller.controller.settings.idz, TableInverseDeadZone)

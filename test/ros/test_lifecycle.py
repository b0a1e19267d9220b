"""The controller as a managed lifecycle node: in-process and from an outside client."""

import math

from hydro_sdp.ros.controller_node import PipControllerNode
from hydro_sdp.ros.plant_node import PlantNode
from hydro_sdp.ros.testing import Lockstep, RosHarness
from lifecycle_msgs.msg import Transition
from lifecycle_msgs.srv import ChangeState, GetState
from outside import MODELS
import pytest
from std_msgs.msg import Float64

pytestmark = pytest.mark.ros

JOINTS = ['boom', 'dipper']


@pytest.fixture
def ros():
    """Return a harness with its own context, closed after the test."""
    with RosHarness() as harness:
        yield harness


def _commands(ros):
    received = {joint: [] for joint in JOINTS}
    helper = ros.helper('commands')
    for joint in JOINTS:
        helper.create_subscription(Float64, f'{joint}/valve_command',
                                   lambda m, j=joint: received[j].append(m.data), 100)
    return received


def test_without_autostart_the_node_waits_unconfigured(ros):
    controller = ros.add(PipControllerNode, parameters={'autostart': False})
    assert controller.state_label() == 'unconfigured' and controller.loops == []
    assert not controller.has_parameter('gains.k_i')
    assert controller.count_publishers('j2/valve_command') == 0
    assert ros.transition(controller, 'configure') == 'inactive'
    assert controller.has_parameter('gains.k_i') and controller.has_parameter('j2.gains.k_i')
    assert controller.count_publishers('j2/valve_command') == 1
    assert ros.transition(controller, 'cleanup') == 'unconfigured'
    assert not controller.has_parameter('j2.gains.k_i')
    assert controller.count_publishers('j2/valve_command') == 0
    assert ros.transition(controller, 'configure') == 'inactive'
    assert ros.transition(controller, 'shutdown') == 'finalized'


def test_a_bad_file_fails_configure_and_leaves_the_node_unconfigured(ros, tmp_path):
    controller = ros.add(PipControllerNode, parameters={
        'autostart': False, 'model_file': str(tmp_path / 'missing.yaml')})
    assert ros.transition(controller, 'configure') == 'unconfigured'


def test_deactivate_closes_every_valve_once_and_activate_resumes(ros):
    plant = ros.add(PlantNode, parameters={'model_files': MODELS})
    controller = ros.add(PipControllerNode, parameters={'joints': JOINTS, 'model_files': MODELS})
    commands = _commands(ros)
    loop = Lockstep(ros, plant, controllers=[controller])
    setpoint = ros.helper('setpoint').create_publisher(Float64, 'boom/setpoint', 10)
    count = controller.setpoints_received
    ros.send(setpoint, Float64(data=math.radians(20.0)),
             lambda: controller.setpoints_received > count)
    loop.run(50)
    assert controller.loop('boom').last_command > 100.0        # opening the valve
    sent = {joint: len(commands[joint]) for joint in JOINTS}
    assert ros.transition(controller, 'deactivate') == 'inactive'
    loop.run(50)
    for joint in JOINTS:
        # One closed valve per joint, then nothing.
        assert commands[joint][sent[joint]:] == [controller.loop(joint).rest]
    angles = list(plant.last_angles)
    loop.run(20)
    assert plant.last_angles == angles                           # the arm stands still
    assert ros.transition(controller, 'activate') == 'active'
    loop.run(50)
    for joint in JOINTS:
        assert len(commands[joint]) > sent[joint] + 5             # commanding again
    # After activation each joint holds where it was found.
    boom = controller.loop('boom')
    assert boom.last_setpoint == pytest.approx(angles[0])
    assert abs(boom.controller.last_u) < 1.0                     # no bump


def test_a_client_deactivates_and_activates_the_controller_over_its_services(ros):
    # As ros2 lifecycle set does: the ~/change_state and ~/get_state services.
    plant = ros.add(PlantNode, parameters={'model_files': MODELS})
    controller = ros.add(PipControllerNode, parameters={'joints': JOINTS, 'model_files': MODELS})
    commands = _commands(ros)
    loop = Lockstep(ros, plant, controllers=[controller])
    client = ros.helper('lifecycle_client')
    change = client.create_client(ChangeState, '/pip_controller/change_state')
    get = client.create_client(GetState, '/pip_controller/get_state')
    assert ros.spin_until(lambda: change.service_is_ready() and get.service_is_ready())

    def call(service, request):
        future = service.call_async(request)
        assert ros.spin_until(future.done)
        return future.result()

    def change_to(transition):
        request = ChangeState.Request()
        request.transition.id = transition
        assert call(change, request).success
        return call(get, GetState.Request()).current_state.label

    assert call(get, GetState.Request()).current_state.label == 'active'
    loop.run(100)
    assert all(len(commands[joint]) >= 20 for joint in JOINTS)
    assert change_to(Transition.TRANSITION_DEACTIVATE) == 'inactive'
    assert ros.spin_until(lambda: all(commands[joint][-1] == 0.0 for joint in JOINTS))
    sent = {joint: len(commands[joint]) for joint in JOINTS}
    loop.run(50)                                   # the plant goes on; no command
    assert {joint: len(commands[joint]) for joint in JOINTS} == sent
    assert change_to(Transition.TRANSITION_ACTIVATE) == 'active'
    loop.run(50)
    assert all(len(commands[joint]) >= sent[joint] + 10 for joint in JOINTS)


def test_shutdown_from_active_closes_the_valves_and_releases_everything(ros):
    plant = ros.add(PlantNode, parameters={'model_files': MODELS})
    controller = ros.add(PipControllerNode, parameters={'joints': JOINTS, 'model_files': MODELS})
    commands = _commands(ros)
    loop = Lockstep(ros, plant, controllers=[controller])
    loop.run(20)
    sent = {joint: len(commands[joint]) for joint in JOINTS}
    assert ros.transition(controller, 'shutdown') == 'finalized'
    assert ros.spin_until(lambda: all(len(commands[j]) == sent[j] + 1 for j in JOINTS))
    assert all(commands[joint][-1] == 0.0 for joint in JOINTS)
    assert controller.loops == [] and not controller.has_parameter('boom.gains.k_i')
    assert controller.count_subscribers('joint_states') == 0          # its own is gone

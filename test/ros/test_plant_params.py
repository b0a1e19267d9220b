"""
The plant node's parameters: the writable ones apply from the next tick, the rest are read-only.

In-process on simulated time (known answers to the last digit), set directly and over the
node's parameter services as ``ros2 param set`` calls them (values as messages: an integer
stays an integer), with the command-line arguments ``ros2 run`` passes.
"""

import math

from hydro_sdp.io.model_files import default_model_path, load_model
from hydro_sdp.ros.plant_node import PlantNode
from hydro_sdp.ros.testing import Lockstep, ParameterClient, RosHarness
import numpy as np
import pytest
from rclpy.parameter import Parameter
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64

pytestmark = pytest.mark.ros

SHIFT = [0.3, -0.3]
DELAY = 15            # samples of the model's 0.15 s delay at 0.01 s
COMMAND = 1.2          # V: inside the model's dead-zone [-1.3298, 1.3124], outside the worn one


def _speed(command, shift=(0.0, 0.0)):
    """Return the joint speed the model gives ``command`` with its edges moved, rad/s."""
    static_map = load_model(default_model_path()).static_map
    if shift != (0.0, 0.0):
        static_map = static_map.shifted(tuple(shift))
    return math.radians(float(static_map.rate(np.array([command]))[0]))


def _send(ros, plant, command):
    """Publish one valve command from a node of the test, as a controller would."""
    publisher = ros.helper('commands').create_publisher(Float64, 'j2/valve_command', 10)
    assert ros.spin_until(lambda: publisher.get_subscription_count() >= 1)
    count = plant.commands_received
    publisher.publish(Float64(data=command))
    assert ros.spin_until(lambda: plant.commands_received > count)


@pytest.fixture
def ros():
    """Return a harness with its own context, closed after the test."""
    with RosHarness() as harness:
        yield harness


def test_noise_std_applies_from_the_next_tick(ros):
    plant = ros.add(PlantNode, parameters={'noise_std': 0.0, 'seed': 3})
    loop = Lockstep(ros, plant)
    states = []
    helper = ros.helper()
    helper.create_subscription(JointState, 'joint_states', states.append, 100)
    ros.spin_until(lambda: plant.count_subscribers('joint_states') >= 1)
    loop.run(5)
    assert ros.spin_until(lambda: len(states) >= 5)
    assert [s.position[0] for s in states] == [0.0] * 5
    assert plant.set_parameters([Parameter('noise_std', value=1)])[0].successful  # an int
    assert plant.get_parameter('noise_std').value == 1.0
    loop.run(20)
    assert ros.spin_until(lambda: len(states) >= 25)
    # The noise stream starts at the first noisy tick: the seeded generator's first draws.
    expected = np.random.default_rng([3, 0]).normal(0.0, 1.0, 20)
    np.testing.assert_allclose(np.degrees([s.position[0] for s in states[5:25]]), expected,
                               rtol=0, atol=1e-12)
    assert plant.set_parameters([Parameter('noise_std', value=0.0)])[0].successful
    loop.run(3)
    assert ros.spin_until(lambda: len(states) >= 28)
    assert [s.position[0] for s in states[25:28]] == [0.0] * 3


def test_a_refused_request_applies_nothing(ros):
    plant = ros.add(PlantNode)
    loop = Lockstep(ros, plant)
    _send(ros, plant, COMMAND)
    result = plant.set_parameters_atomically([Parameter('dead_zone_shift', value=SHIFT),
                                              Parameter('noise_std', value=50.0)])
    assert not result.successful and 'noise_std' in result.reason
    result = plant.set_parameters_atomically([Parameter('noise_std', value=0.5),
                                              Parameter('dead_zone_shift', value=[0.3])])
    assert not result.successful and 'two numbers' in result.reason
    assert plant.get_parameter('dead_zone_shift').value == [0.0, 0.0]
    assert plant.get_parameter('noise_std').value == 0.0
    loop.run(40)                                  # past the 0.15 s delay: still at rest
    assert plant.last_angles == [0.0]
    assert plant.set_parameters([Parameter('dead_zone_shift', value=SHIFT)])[0].successful
    angles = [plant.last_angles[0]]
    loop.run(20, lambda k: angles.append(plant.last_angles[0]))
    # Commands from the next tick on meet the worn valve, and act after the 0.15 s delay.
    speeds = np.radians(np.diff(angles)) / 0.01
    assert speeds[:DELAY] == pytest.approx([0.0] * DELAY, abs=0.0)
    assert speeds[DELAY:] == pytest.approx([_speed(COMMAND, SHIFT)] * (20 - DELAY), rel=1e-9)


def test_machine_parameters_are_read_only(ros):
    plant = ros.add(PlantNode)
    for name, value in (('sample_period', 0.02), ('model_file', 'x.yaml'), ('seed', 4),
                        ('model_files', ['a.yaml']), ('initial_angles', [3.0])):
        result = plant.set_parameters([Parameter(name, value=value)])[0]
        assert not result.successful and 'read-only' in result.reason, name


def test_run_time_changes_take_effect_over_the_services():
    with RosHarness(args=['--ros-args', '-p', 'noise_std:=0']) as ros:     # an integer
        plant = ros.add(PlantNode, parameters={'seed': 5})
        client = ParameterClient(ros, 'hydro_plant')
        assert client.get('noise_std') == [(Parameter.Type.DOUBLE, 0.0)]
        states = []
        helper = ros.helper('outside')
        helper.create_subscription(JointState, 'joint_states', states.append, 1000)
        commands = helper.create_publisher(Float64, 'j2/valve_command', 10)
        loop = Lockstep(ros, plant)
        assert ros.spin_until(lambda: commands.get_subscription_count() >= 1)

        def next_states(count):
            start = len(states)
            loop.run(count)
            assert ros.spin_until(lambda: len(states) >= start + count)
            return states[start:start + count]

        assert len({s.position[0] for s in next_states(30)}) == 1        # a perfect sensor
        assert client.set_atomically(noise_std=1).successful              # an integer
        assert client.get('noise_std') == [(Parameter.Type.DOUBLE, 1.0)]
        noisy = np.degrees([s.position[0] for s in next_states(400)])
        assert np.std(noisy) == pytest.approx(1.0, rel=0.15)
        assert client.set_atomically(noise_std=0.0).successful
        assert len({s.position[0] for s in next_states(30)}) == 1
        # The valve: a command inside the dead-zone holds the joint until the edges move.
        count = plant.commands_received
        commands.publish(Float64(data=COMMAND))
        assert ros.spin_until(lambda: plant.commands_received > count)
        assert all(s.velocity[0] == 0.0 for s in next_states(50))
        result = client.set_atomically(dead_zone_shift=SHIFT, noise_std=50.0)
        assert not result.successful and 'noise_std' in result.reason
        assert all(s.velocity[0] == 0.0 for s in next_states(30))
        assert client.get('dead_zone_shift', 'noise_std') == [
            (Parameter.Type.DOUBLE_ARRAY, [0.0, 0.0]), (Parameter.Type.DOUBLE, 0.0)]
        assert client.set_atomically(dead_zone_shift=SHIFT).successful
        moving = next_states(DELAY + 10)[DELAY:]
        assert [s.velocity[0] for s in moving] == pytest.approx([_speed(COMMAND, SHIFT)] * 10,
                                                                rel=1e-9)
        result = client.set_atomically(seed=5)
        assert not result.successful and 'read-only' in result.reason


def test_a_dead_zone_shift_given_at_start_up_takes_effect(ros):
    plant = ros.add(PlantNode, parameters={'dead_zone_shift': SHIFT})
    loop = Lockstep(ros, plant)
    _send(ros, plant, COMMAND)
    angles = [plant.last_angles[0]]
    loop.run(DELAY + 10, lambda k: angles.append(plant.last_angles[0]))
    speeds = np.radians(np.diff(angles)) / 0.01
    assert speeds[-5:] == pytest.approx([_speed(COMMAND, SHIFT)] * 5, rel=1e-9)


def test_a_silent_source_closes_the_valve(ros):
    plant = ros.add(PlantNode, parameters={'command_timeout': 0.2, 'initial_angles': [10.0]})
    loop = Lockstep(ros, plant)
    _send(ros, plant, 3.0)
    angles = [plant.last_angles[0]]
    loop.run(60, lambda k: angles.append(plant.last_angles[0]))
    moving = np.diff(angles)
    # Driven after the 0.15 s delay; 0.2 s after the command the valve closes, and the joint
    # stops a delay later.
    assert moving[20] > 0.0 and np.all(moving[40:] == 0.0)


def test_commands_from_a_node_other_than_the_named_source_are_refused(ros):
    plant = ros.add(PlantNode, parameters={'command_source': '/pip_controller',
                                           'initial_angles': [10.0]})
    _send(ros, plant, 3.0)                      # from /commands, not /pip_controller
    assert plant.commands_refused == 1
    Lockstep(ros, plant).run(40)
    assert plant.last_angles == [10.0]

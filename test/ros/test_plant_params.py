"""
The plant node's parameters: the writable ones apply from the next tick, the rest are read-only.

In-process on simulated time (known answers to the last digit), and over the parameter
services of a ``plant_node`` process from an outside rclpy client (what ``ros2 param set``
does).
"""

import math
import time

from hydro_sdp.io.model_files import default_model_path, load_model
from hydro_sdp.ros.plant_node import PlantNode
from hydro_sdp.ros.testing import Lockstep, RosHarness
import numpy as np
from outside import node_process_fixture, NodeProcess
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
    plant._on_command(0, Float64(data=COMMAND))
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


class _OutsidePlant(NodeProcess):
    """A plant_node process, and a client in this process on the same fresh domain."""

    def __init__(self, monkeypatch, *arguments):
        super().__init__(monkeypatch, 'plant_node', 'hydro_plant', *arguments)
        self.states = []
        self.node.create_subscription(JointState, 'joint_states', self.states.append, 1000)
        self.commands = self.node.create_publisher(Float64, 'j2/valve_command', 10)
        self.wait_until_up(lambda: len(self.states) > 0
                           and self.commands.get_subscription_count() >= 1)

    def next_states(self, count):
        """Return the next ``count`` joint_states published (after this call)."""
        start = len(self.states)
        assert self.spin_until(lambda: len(self.states) >= start + count, 20.0)
        return self.states[start:start + count]

    def close(self):
        super().close()
        assert self.process.returncode == 0


@pytest.fixture
def outside(monkeypatch):
    """Start a plant_node process and an outside client; stop both after the test."""
    yield from node_process_fixture(_OutsidePlant, monkeypatch)


@pytest.mark.slow
def test_run_time_changes_take_effect_over_the_services(outside):
    plant = outside('-p', 'noise_std:=0')
    assert len({s.position[0] for s in plant.next_states(30)}) == 1      # a perfect sensor
    assert plant.set_atomically(noise_std=1).successful                  # an integer
    assert plant.get('noise_std') == [(Parameter.Type.DOUBLE, 1.0)]
    plant.next_states(3)                        # ticks that may predate the change
    noisy = np.degrees([s.position[0] for s in plant.next_states(400)])
    assert np.std(noisy) == pytest.approx(1.0, rel=0.15)
    assert plant.set_atomically(noise_std=0.0).successful
    plant.next_states(3)
    assert len({s.position[0] for s in plant.next_states(30)}) == 1

    # The valve: a command inside the dead-zone holds the joint until the edges move.
    def hold(seconds):
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            plant.commands.publish(Float64(data=COMMAND))
            plant.spin_until(lambda: False, 0.05)
    hold(0.5)
    assert all(s.velocity[0] == 0.0 for s in plant.next_states(10))
    result = plant.set_atomically(dead_zone_shift=SHIFT, noise_std=50.0)
    assert not result.successful and 'noise_std' in result.reason
    hold(0.3)
    assert all(s.velocity[0] == 0.0 for s in plant.next_states(10))
    assert plant.get('dead_zone_shift', 'noise_std') == [
        (Parameter.Type.DOUBLE_ARRAY, [0.0, 0.0]), (Parameter.Type.DOUBLE, 0.0)]
    assert plant.set_atomically(dead_zone_shift=SHIFT).successful
    hold(0.3)
    moving = plant.next_states(10)
    assert [s.velocity[0] for s in moving] == pytest.approx([_speed(COMMAND, SHIFT)] * 10,
                                                            rel=1e-6)
    result = plant.set_atomically(seed=5)
    assert not result.successful and 'read-only' in result.reason

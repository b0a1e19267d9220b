"""The plant node at the ROS boundary: JointState velocity in rad/s, angles in degrees."""

import math

from hydro_sdp.io.model_files import default_model_path, load_model
from hydro_sdp.ros.controller_node import PipControllerNode
from hydro_sdp.ros.plant_node import PlantNode
from hydro_sdp.ros.testing import Lockstep, RosHarness
import numpy as np
import pytest
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64

pytestmark = pytest.mark.ros


@pytest.fixture
def ros():
    """Return a harness with its own context, closed after the test."""
    with RosHarness() as harness:
        yield harness


def test_joint_state_velocity_is_the_simulated_motion_over_the_last_sample(ros):
    plant = ros.add(PlantNode, parameters={'noise_std': 0.5, 'initial_angles': [10.0]})
    helper = ros.helper('listener')
    states = []
    helper.create_subscription(JointState, 'joint_states', states.append, 100)
    publisher = helper.create_publisher(Float64, 'j2/valve_command', 10)
    loop = Lockstep(ros, plant)
    assert ros.spin_until(lambda: publisher.get_subscription_count() >= 1)
    publisher.publish(Float64(data=5.0))
    assert ros.spin_until(lambda: plant.commands_received == 1)
    angles = []
    loop.run(60, on_step=lambda k: angles.append(plant.last_angles[0]))
    assert ros.spin_until(lambda: len(states) >= 60)
    velocity = np.array([state.velocity[0] for state in states[:60]])
    # Noise-free motion, rad/s: 0 before the first step, then (y_k - y_{k-1}) / dt.
    expected = np.radians(np.diff(np.r_[10.0, angles]) / 0.01)
    np.testing.assert_allclose(velocity, expected, rtol=0, atol=1e-9)
    assert velocity[0] == 0.0 and velocity[:15].max() == 0.0         # 0.15 s pure delay
    speed = load_model(default_model_path()).rate(np.array([5.0]))[0]
    assert velocity[-1] == pytest.approx(math.radians(speed), rel=1e-9)


def test_angle_parameters_are_documented_in_degrees(ros):
    plant = ros.add(PlantNode)
    controller = ros.add(PipControllerNode)
    for node, names in ((plant, ('noise_std', 'initial_angles')),
                        (controller, ('setpoint_margin', 'idz.slopes', 'idz.beta',
                                      'gains.f', 'gains.k_i'))):
        for name in names:
            description = node.describe_parameter(name).description
            assert 'deg' in description and 'rad' not in description, (name, description)


def test_the_plant_runs_the_model_files_oscillation(ros, tmp_path):
    # J2 whose link rings at 2 Hz: the node builds its simulator from the file, so the
    # published angles are the ringing model's (stepped offline here), not the plain one's.
    from hydro_sdp.core.model.effects import Oscillation
    from hydro_sdp.core.model.simulation import JointSimulator
    from hydro_sdp.io.model_files import save_model

    model = load_model(default_model_path()).with_effect(Oscillation(2.0, 0.1))
    path = save_model(model, tmp_path / 'ringing.yaml')
    plant = ros.add(PlantNode, parameters={'model_file': str(path), 'noise_std': 0.0,
                                           'initial_angles': [10.0]})
    publisher = ros.helper('commands').create_publisher(Float64, 'j2/valve_command', 10)
    loop = Lockstep(ros, plant)
    assert ros.spin_until(lambda: publisher.get_subscription_count() >= 1)
    publisher.publish(Float64(data=5.0))
    assert ros.spin_until(lambda: plant.commands_received == 1)
    angles = []
    loop.run(80, on_step=lambda k: angles.append(plant.last_angles[0]))
    offline = {}
    for name, joint in (('ringing', model), ('plain', model.without_effect('oscillation'))):
        simulator = JointSimulator(joint, 0.01, 10.0, v_before=joint.rest_command)
        offline[name] = np.r_[10.0, [simulator.step(5.0) for _ in range(79)]]
    np.testing.assert_allclose(angles, offline['ringing'], rtol=0, atol=1e-9)
    assert np.abs(offline['ringing'] - offline['plain']).max() > 0.05

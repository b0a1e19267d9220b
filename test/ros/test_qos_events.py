"""
QoS event handlers: kept where a mismatch can happen, left out in the in-process harness.

A node's subscription in its own context keeps rclpy's default handlers, which warn of a
publisher whose QoS cannot match (a best-effort sensor driver's joint_states); in a
:class:`~hydro_sdp.ros.testing.RosHarness` every publisher is one of its nodes, and its
subscriptions go without them (docs/methods.md section 9.4).
"""

import time

from hydro_sdp.ros.controller_node import PipControllerNode
from hydro_sdp.ros.testing import RosHarness
import pytest
import rclpy
from rclpy.context import Context
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import JointState
from support.domains import fresh_domain

pytestmark = pytest.mark.ros


def test_a_node_in_its_own_context_warns_of_a_best_effort_joint_states(capfd):
    # A sensor driver that publishes best effort never reaches the reliable subscription:
    # the controller's log says so, naming the topic and the policy. Read where the log
    # prints it (stderr): its copy on /rosout, one message right after discovery, does not
    # always reach a listener, as rcl's own tests found (ros2/rcl#1050).
    context = Context()
    rclpy.init(context=context, domain_id=fresh_domain())
    executor = SingleThreadedExecutor(context=context)
    printed = ''
    try:
        node = PipControllerNode(context=context)
        driver = Node('sensor_driver', context=context)
        driver.create_publisher(JointState, '/joint_states',
                                QoSProfile(depth=10, reliability=ReliabilityPolicy.BEST_EFFORT))
        executor.add_node(node)
        executor.add_node(driver)
        deadline = time.monotonic() + 30.0  # discovery on a loaded host
        while time.monotonic() < deadline and not _warned(printed, node.get_name()):
            executor.spin_once(timeout_sec=0.1)
            printed += capfd.readouterr().err
    finally:
        executor.shutdown()
        rclpy.try_shutdown(context=context)
    warning = _warned(printed, node.get_name())
    assert warning and "topic 'joint_states'" in warning and 'RELIABILITY' in warning, printed


def _warned(printed, name):
    """Return the first line of ``printed`` in which node ``name`` warns of incompatible QoS."""
    return next((line for line in printed.splitlines()
                 if f'[{name}]' in line and 'incompatible QoS' in line), None)


def test_the_harness_nodes_subscribe_without_handlers():
    with RosHarness() as ros:
        controller = ros.add(PipControllerNode)
        own = [s for s in controller.subscriptions
               if s.topic_name in ('/j2/setpoint', '/joint_states', '/joint_trajectory')]
        assert len(own) == 3 and not any(s.event_handlers for s in own)
    # Leaving the harness destroyed the node and its subscriptions without an error.

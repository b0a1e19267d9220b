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
from rcl_interfaces.msg import Log
import rclpy
from rclpy.context import Context
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import JointState
from support.domains import fresh_domain

pytestmark = pytest.mark.ros


def test_a_node_in_its_own_context_warns_of_a_best_effort_joint_states():
    # A sensor driver that publishes best effort never reaches the reliable subscription:
    # the controller says so on /rosout, naming the topic and the policy.
    context = Context()
    rclpy.init(context=context, domain_id=fresh_domain())
    executor = SingleThreadedExecutor(context=context)
    try:
        # The listener first, so that the controller's log finds it already there.
        driver = Node('sensor_driver', context=context)
        warnings = []
        listener = driver.create_subscription(
            Log, '/rosout', lambda log: warnings.append(log.msg) if log.name == node.get_name()
            and 'incompatible QoS' in log.msg else None,
            QoSProfile(depth=100, durability=DurabilityPolicy.TRANSIENT_LOCAL))
        node = PipControllerNode(context=context)
        # The listener matched to both nodes' /rosout before the warning is due: a log kept
        # for late joiners lives 10 s, which discovery on a loaded host can outlast.
        deadline = time.monotonic() + 30.0
        while listener.get_publisher_count() < 2 and time.monotonic() < deadline:
            time.sleep(0.05)
        driver.create_publisher(JointState, '/joint_states',
                                QoSProfile(depth=10, reliability=ReliabilityPolicy.BEST_EFFORT))
        executor.add_node(node)
        executor.add_node(driver)
        deadline = time.monotonic() + 30.0  # discovery on a loaded host
        while not warnings and time.monotonic() < deadline:
            executor.spin_once(timeout_sec=0.1)
    finally:
        executor.shutdown()
        rclpy.try_shutdown(context=context)
    assert warnings and 'joint_states' in warnings[0] and 'RELIABILITY' in warnings[0], \
        warnings


def test_the_harness_nodes_subscribe_without_handlers():
    with RosHarness() as ros:
        controller = ros.add(PipControllerNode)
        own = [s for s in controller.subscriptions
               if s.topic_name in ('/j2/setpoint', '/joint_states', '/joint_trajectory')]
        assert len(own) == 3 and not any(s.event_handlers for s in own)
    # Leaving the harness destroyed the node and its subscriptions without an error.

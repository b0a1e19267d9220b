"""
QoS event handlers: kept where a mismatch can happen, left out in the in-process harness.

A node's subscription in its own context keeps rclpy's default handlers, which warn of a
publisher whose QoS cannot match (a best-effort sensor driver's joint_states); in a
:class:`~hydro_sdp.ros.testing.RosHarness` every publisher is one of its nodes, and its
subscriptions go without them (docs/methods.md section 9.4).
"""

from hydro_sdp.ros.controller_node import PipControllerNode
from hydro_sdp.ros.testing import RosHarness
import pytest
import rclpy
from rclpy.context import Context

pytestmark = pytest.mark.ros


def _topics_with_handlers(node):
    return sorted(s.topic_name for s in node.subscriptions if s.event_handlers)


def test_a_node_in_its_own_context_keeps_the_mismatch_warnings():
    context = Context()
    rclpy.init(context=context, domain_id=211)
    try:
        node = PipControllerNode(context=context)
        try:
            with_handlers = _topics_with_handlers(node)
        finally:
            node.destroy_node()
    finally:
        rclpy.try_shutdown(context=context)
    assert {'/j2/setpoint', '/joint_states', '/joint_trajectory'} <= set(with_handlers)


def test_the_harness_nodes_subscribe_without_handlers():
    with RosHarness() as ros:
        controller = ros.add(PipControllerNode)
        own = [s for s in controller.subscriptions
               if s.topic_name in ('/j2/setpoint', '/joint_states', '/joint_trajectory')]
        assert len(own) == 3 and not any(s.event_handlers for s in own)
    # Leaving the harness destroyed the node and its subscriptions without an error.

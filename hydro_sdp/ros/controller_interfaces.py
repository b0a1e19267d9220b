"""The topics and timers of a controller node, made at configure, destroyed at cleanup."""

from __future__ import annotations

from functools import partial
from typing import Callable

from hydro_sdp.core.control.scheduling import watchdog_period_ns
from hydro_sdp.ros import qos
from hydro_sdp.ros.conversions import CONTROLLER_STATE_LABELS
from hydro_sdp.ros.joint_loop import JointLoop
from rclpy.clock import Clock, ClockType
from rclpy.node import Node
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64, Float64MultiArray, MultiArrayDimension
from trajectory_msgs.msg import JointTrajectory


def controller_state_message() -> Float64MultiArray:
    """Return a ``<joint>/controller_state`` message with its layout set, to be filled."""
    message = Float64MultiArray()
    size = len(CONTROLLER_STATE_LABELS)
    message.layout.dim = [MultiArrayDimension(label=','.join(CONTROLLER_STATE_LABELS),
                                              size=size, stride=size)]
    return message


class ControllerInterfaces:
    """
    Publishers, subscriptions and the watchdog of a configured controller.

    ``on_setpoint``: called with a ``<joint>/setpoint`` message and the joint's loop.
    ``timeout_ns``: feedback timeout, ns (the watchdog runs at :func:`watchdog_period_ns` of it).
    """

    def __init__(self, node: Node, loops: list[JointLoop], *,
                 on_state: Callable[[JointState], None],
                 on_setpoint: Callable[[Float64, JointLoop], None],
                 on_trajectory: Callable[[JointTrajectory], None],
                 on_watchdog: Callable[[], None], timeout_ns: int) -> None:
        self._node = node
        self._publishers = []
        self._subscriptions = []
        events = qos.subscription_events(node.context)
        for loop in loops:
            loop.command_pub = node.create_publisher(
                Float64, f'{loop.joint}/valve_command', qos.COMMAND_QOS,
                event_callbacks=qos.QUIET_PUBLISHER)
            loop.state_pub = node.create_publisher(
                Float64MultiArray, f'{loop.joint}/controller_state', qos.COMMAND_QOS,
                event_callbacks=qos.QUIET_PUBLISHER)
            self._publishers += [loop.command_pub, loop.state_pub]
            self._subscriptions.append(node.create_subscription(
                Float64, f'{loop.joint}/setpoint',
                partial(self._setpoint, on_setpoint, loop), qos.COMMAND_QOS,
                event_callbacks=events))
        self._subscriptions.append(node.create_subscription(
            JointState, 'joint_states', on_state, qos.STATE_QOS, event_callbacks=events))
        self._subscriptions.append(node.create_subscription(
            JointTrajectory, 'joint_trajectory', on_trajectory, qos.COMMAND_QOS,
            event_callbacks=events))
        period = watchdog_period_ns(timeout_ns) * 1e-9
        self.watchdog = node.create_timer(period, on_watchdog)
        self.steady_watchdog = node.create_timer(period, on_watchdog,
                                                 clock=Clock(clock_type=ClockType.STEADY_TIME))
        #: The message every joint's controller_state is filled into.
        self.state_message = controller_state_message()

    @staticmethod
    def _setpoint(callback: Callable[[Float64, JointLoop], None], loop: JointLoop,
                  message: Float64) -> None:
        callback(message, loop)

    def set_timeout(self, timeout_ns: int) -> None:
        """Run the watchdog at the period of a new feedback timeout."""
        self.watchdog.timer_period_ns = watchdog_period_ns(timeout_ns)
        self.steady_watchdog.timer_period_ns = watchdog_period_ns(timeout_ns)

    def destroy(self, loops: list[JointLoop]) -> None:
        """Destroy every topic and the watchdog."""
        node = self._node
        node.destroy_timer(self.watchdog)
        node.destroy_timer(self.steady_watchdog)
        for subscription in self._subscriptions:
            node.destroy_subscription(subscription)
        for publisher in self._publishers:
            node.destroy_publisher(publisher)
        for loop in loops:
            loop.command_pub = loop.state_pub = None

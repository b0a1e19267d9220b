"""``/diagnostics`` of the nodes: DiagnosticArray from joints' health statuses."""

from __future__ import annotations

from typing import Callable, Sequence

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from hydro_sdp.core.control.health import HealthStatus
from hydro_sdp.ros import qos
from hydro_sdp.ros.conversions import fill_stamp
from rclpy.node import Node


def diagnostic_status(node_name: str, joint: str, health: HealthStatus) -> DiagnosticStatus:
    """Return one joint's status: name ``<node>: <joint>``, hardware_id the joint."""
    return DiagnosticStatus(level=bytes([health.level]), name=f'{node_name}: {joint}',
                            message=health.message, hardware_id=joint,
                            values=[KeyValue(key=k, value=v) for k, v in health.values])


def diagnostic_array(stamp_ns: int, node_name: str, joints: Sequence[str],
                     statuses: Sequence[HealthStatus]) -> DiagnosticArray:
    """Return a ``DiagnosticArray`` stamped ``stamp_ns`` with one status per joint."""
    array = DiagnosticArray()
    fill_stamp(array.header.stamp, stamp_ns)
    array.status = [diagnostic_status(node_name, joint, health)
                    for joint, health in zip(joints, statuses)]
    return array


class DiagnosticsReporter:
    """
    A node's ``/diagnostics``: one status per joint every ``period`` seconds.

    ``period``: time between reports, s.
    ``statuses``: called with the node clock's reading (ns); returns ``(joint, HealthStatus)``
    pairs.
    """

    def __init__(self, node: Node, period: float,
                 statuses: Callable[[int], Sequence[tuple[str, HealthStatus]]]) -> None:
        self._node = node
        self._statuses = statuses
        self._publisher = node.create_publisher(DiagnosticArray, '/diagnostics',
                                                qos.DIAGNOSTICS_QOS,
                                                event_callbacks=qos.QUIET_PUBLISHER)
        self._timer = node.create_timer(period, self.publish)

    def publish(self) -> None:
        """Publish one status per joint now."""
        node = self._node
        now = node.get_clock().now().nanoseconds
        pairs = self._statuses(now)
        self._publisher.publish(diagnostic_array(now, node.get_name(),
                                                 [joint for joint, _ in pairs],
                                                 [health for _, health in pairs]))

    def destroy(self) -> None:
        """Stop reporting."""
        self._node.destroy_timer(self._timer)
        self._node.destroy_publisher(self._publisher)

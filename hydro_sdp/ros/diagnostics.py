"""DiagnosticArray from :class:`~hydro_sdp.core.control.health.HealthStatus`."""

from __future__ import annotations

from typing import Sequence

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from hydro_sdp.core.control.health import HealthStatus
from hydro_sdp.ros.conversions import fill_stamp


def diagnostic_status(node_name: str, joint: str, health: HealthStatus) -> DiagnosticStatus:
    """
    Return one joint's status: name ``<node>: <joint>``, hardware_id the joint.

    Parameters
    ----------
    node_name : str
        Name of the reporting node.
    joint : str
        Joint name.
    health : HealthStatus
        Level, message and key-values from :func:`~hydro_sdp.core.control.health.joint_health`.

    Returns
    -------
    diagnostic_msgs/DiagnosticStatus
        The status.

    """
    return DiagnosticStatus(level=bytes([health.level]), name=f'{node_name}: {joint}',
                            message=health.message, hardware_id=joint,
                            values=[KeyValue(key=k, value=v) for k, v in health.values])


def diagnostic_array(stamp_ns: int, node_name: str, joints: Sequence[str],
                     statuses: Sequence[HealthStatus]) -> DiagnosticArray:
    """
    Return a ``DiagnosticArray`` stamped ``stamp_ns`` with one status per joint.

    Parameters
    ----------
    stamp_ns : int
        Stamp, ns.
    node_name : str
        Name of the reporting node.
    joints : sequence of str
        Joint names, in the order of ``statuses``.
    statuses : sequence of HealthStatus
        One status per joint.

    Returns
    -------
    diagnostic_msgs/DiagnosticArray
        The message.

    """
    array = DiagnosticArray()
    fill_stamp(array.header.stamp, stamp_ns)
    array.status = [diagnostic_status(node_name, joint, health)
                    for joint, health in zip(joints, statuses)]
    return array

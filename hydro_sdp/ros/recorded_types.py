"""The message types the recorder records, and the type each of hydro_sdp's topics must have."""

from __future__ import annotations

import importlib
from typing import Sequence

#: Every type the recorder records: the types of hydro_sdp's topics, and a few plain ones.
RECORDABLE: dict[str, tuple[str, str]] = {name: (name.rsplit('/', 1)[0].replace('/', '.'),
                                                 name.rsplit('/', 1)[1]) for name in (
    'sensor_msgs/msg/JointState',
    'std_msgs/msg/Float64', 'std_msgs/msg/Float64MultiArray', 'std_msgs/msg/Float32',
    'std_msgs/msg/Bool', 'std_msgs/msg/Int32', 'std_msgs/msg/Int64', 'std_msgs/msg/String',
    'trajectory_msgs/msg/JointTrajectory', 'diagnostic_msgs/msg/DiagnosticArray',
    'rosgraph_msgs/msg/Clock', 'rcl_interfaces/msg/Log',
)}

#: The type of each of hydro_sdp's topics, by the last part of its name.
EXPECTED = {
    'joint_states': 'sensor_msgs/msg/JointState',
    'valve_command': 'std_msgs/msg/Float64',
    'setpoint': 'std_msgs/msg/Float64',
    'controller_state': 'std_msgs/msg/Float64MultiArray',
    'joint_trajectory': 'trajectory_msgs/msg/JointTrajectory',
    'diagnostics': 'diagnostic_msgs/msg/DiagnosticArray',
    'clock': 'rosgraph_msgs/msg/Clock',
    'rosout': 'rcl_interfaces/msg/Log',
}


def expected_type(topic: str) -> str | None:
    """Return the type ``topic`` must have (``/arm/boom/valve_command``: Float64), or None."""
    return EXPECTED.get(topic.rstrip('/').rsplit('/', 1)[-1])


def choose_type(topic: str, advertised: Sequence[str]) -> tuple[str | None, str]:
    """
    Return the type to record ``topic`` with, from the types it is advertised with.

    Returns: the type (None: none can be recorded) and, when there is a problem, why (''
    otherwise).
    """
    expected = expected_type(topic)
    if expected is not None:
        if expected in advertised:
            others = [name for name in advertised if name != expected]
            return expected, (f"{topic} is also advertised as {', '.join(others)}; recording "
                              f'{expected}' if others else '')
        return None, (f"{topic} is advertised as {', '.join(advertised)}, not {expected}: not "
                      'recorded until a publisher of that type appears')
    known = [name for name in advertised if name in RECORDABLE]
    if not known:
        return None, (f"{topic} is advertised as {', '.join(advertised)}, a type the recorder "
                      f"does not record (it records {', '.join(sorted(RECORDABLE))})")
    return known[0], (f"{topic} is advertised with several types ({', '.join(advertised)}); "
                      f'recording {known[0]}' if len(advertised) > 1 else '')


def message_class(msgtype: str) -> type:
    """Import the Python class of a type of :data:`RECORDABLE`."""
    module, name = RECORDABLE[msgtype]
    cls: type = getattr(importlib.import_module(module), name)
    return cls

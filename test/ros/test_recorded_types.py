"""The recorder's types: hydro_sdp's topics with theirs only, nothing by the graph's word."""

import importlib

from hydro_sdp.ros.recorded_types import choose_type, expected_type, message_class, RECORDABLE
import pytest
from sensor_msgs.msg import JointState
from std_msgs.msg import Bool


def test_the_topics_of_hydro_sdp_are_recorded_with_their_type_only():
    assert expected_type('/arm2/boom/valve_command') == 'std_msgs/msg/Float64'
    assert choose_type('/joint_states', ['sensor_msgs/msg/JointState']) == \
        ('sensor_msgs/msg/JointState', '')
    msgtype, why = choose_type('/joint_states', ['builtin_interfaces/msg/Time'])
    assert msgtype is None and why == ('/joint_states is advertised as builtin_interfaces/msg/'
                                       'Time, not sensor_msgs/msg/JointState: not recorded '
                                       'until a publisher of that type appears')
    msgtype, why = choose_type('/j2/setpoint', ['std_msgs/msg/Float32', 'std_msgs/msg/Float64'])
    assert msgtype == 'std_msgs/msg/Float64' and 'also advertised as std_msgs/msg/Float32' in why


def test_other_topics_keep_their_type_if_the_recorder_records_it():
    assert choose_type('/flag', ['std_msgs/msg/Bool']) == ('std_msgs/msg/Bool', '')
    msgtype, why = choose_type('/cmd', ['os/msg/system'])
    assert msgtype is None and 'a type the recorder does not record' in why


def test_classes_come_from_the_table_and_nothing_else_is_imported(monkeypatch):
    assert message_class('sensor_msgs/msg/JointState') is JointState
    assert message_class('std_msgs/msg/Bool') is Bool
    imported = []
    monkeypatch.setattr(importlib, 'import_module', lambda name: imported.append(name))
    for name in ('os/msg/system', 'builtin_interfaces/msg/Time', '../../x/msg/y'):
        with pytest.raises(KeyError):
            message_class(name)
    assert imported == []
    assert all(module.endswith('.msg') for module, _ in RECORDABLE.values())

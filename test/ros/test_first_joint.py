"""The one-joint property of the multi-joint nodes: reads (and may write) the first joint."""

from types import SimpleNamespace

from hydro_sdp.ros.first_joint import first_joint
import pytest


class _Node:
    """Two joints; the one-joint names point at the first."""

    name = first_joint('joints', 'name', "The first joint's name.")
    blind = first_joint('joints', 'gate.blind', "The first joint's gate state.")
    estimator = first_joint('joints', 'estimator', "The first joint's estimator.", settable=True)

    def __init__(self):
        self.joints = [SimpleNamespace(name='boom', gate=SimpleNamespace(blind=True), estimator=1),
                       SimpleNamespace(name='dipper', gate=SimpleNamespace(blind=False),
                                       estimator=2)]


def test_reads_the_first_joint_plain_and_nested():
    node = _Node()
    assert node.name == 'boom' and node.blind is True
    node.joints.reverse()
    assert node.name == 'dipper' and node.blind is False


def test_a_settable_name_writes_the_first_joint_only():
    node = _Node()
    node.estimator = 7
    assert [joint.estimator for joint in node.joints] == [7, 2]


def test_other_names_are_read_only_and_documented():
    node = _Node()
    with pytest.raises(AttributeError):
        node.name = 'arm'
    assert node.joints[0].name == 'boom'
    assert _Node.name.__doc__ == "The first joint's name."

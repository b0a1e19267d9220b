"""
The shipped params file, as ``ros2 run`` users load it: every node, in a namespace, under ``-p``.

The file lists every parameter with a fixed default, with its value, and marks where the
shipped setup departs from a default. These tests hold it against the nodes themselves
(what each declares without the file), not against the tables it is written from, and load
it as ``ros2 run`` does: as arguments of the process's context (``rclpy.init(args=...)``),
which every node of the process reads.
"""

from pathlib import Path

from conftest import REPO
from hydro_sdp.bags import write_bag
from hydro_sdp.core.model.records import Record
from hydro_sdp.ros.bag_player import BagPlayerNode
from hydro_sdp.ros.bag_recorder import BagRecorderNode
from hydro_sdp.ros.controller_node import PipControllerNode
from hydro_sdp.ros.identifier_node import IdentifierNode
from hydro_sdp.ros.plant_node import PlantNode
from hydro_sdp.ros.testing import RosHarness
import numpy as np
import pytest
import yaml

pytestmark = pytest.mark.ros

PARAMS = REPO / 'config' / 'hydro_sdp.yaml'
NODES = {'hydro_plant': PlantNode, 'pip_controller': PipControllerNode,
         'sdp_identifier': IdentifierNode, 'bag_recorder': BagRecorderNode,
         'bag_player': BagPlayerNode}
#: Where the shipped setup departs from the defaults, as the file's header says.
SHIPPED = {('hydro_plant', 'noise_std'): 0.02, ('hydro_plant', 'seed'): 1,
           ('sdp_identifier', 'noise_std'): 0.02}


@pytest.fixture(scope='module')
def listed():
    """Return the file's values by node name."""
    document = yaml.safe_load(PARAMS.read_text())
    assert sorted(document) == sorted(f'/**/{name}' for name in NODES)
    return {key[len('/**/'):]: section['ros__parameters'] for key, section in document.items()}


@pytest.fixture(scope='module')
def bag(tmp_path_factory):
    """Return a small bag for the player (it refuses to start without one)."""
    t = np.arange(1, 21) * 0.01
    record = Record(t=t, v=np.zeros(20), y=np.zeros(20), joint='j2')
    return str(write_bag(tmp_path_factory.mktemp('bag') / 'played', [record]))


def _add_every_node(ros, bag, folder):
    """Add one node of each executable; return them, and the values the test set itself."""
    given = {'bag_recorder': {'output': str(Path(folder) / 'recorded')},
             'bag_player': {'bag': bag, 'autostart': False}}
    nodes = {name: ros.add(cls, parameters=given.get(name)) for name, cls in NODES.items()}
    return nodes, {(name, key) for name, values in given.items() for key in values}


def test_the_file_lists_each_default_of_every_node_and_marks_what_it_changes(
        listed, bag, tmp_path):
    text = PARAMS.read_text()
    with RosHarness() as ros:
        nodes, given = _add_every_node(ros, bag, tmp_path)
        for name, values in listed.items():
            node = nodes[name]
            for parameter, value in values.items():
                if (name, parameter) in given:
                    continue
                default = node.get_parameter(parameter).value
                if (name, parameter) in SHIPPED:
                    assert value == SHIPPED[name, parameter] != default
                    assert f'shipped (default {default}' in text
                else:
                    assert value == pytest.approx(default), (name, parameter)
    # Every writable parameter of the controller is in the file, so the README's
    # --params-file example names what a user would change.
    assert {'feedback_timeout', 'setpoint_margin', 'feedforward'} <= set(listed['pip_controller'])
    # The per-joint gains, files and joint names have no fixed default: comments only.
    assert 'gains.k_i' not in listed['pip_controller'] and '<joint>.gains.k_i' in text


def test_every_node_loads_the_file_as_ros2_run_passes_it(listed, bag, tmp_path):
    with RosHarness(args=['--ros-args', '--params-file', str(PARAMS)]) as ros:
        nodes, given = _add_every_node(ros, bag, tmp_path)
        for name, values in listed.items():
            for parameter, value in values.items():
                if (name, parameter) not in given:
                    assert nodes[name].get_parameter(parameter).value == pytest.approx(value)
        assert nodes['pip_controller'].joint == 'j2'
        assert nodes['pip_controller'].state_label() == 'active'


@pytest.mark.parametrize('arguments, expected', [
    # In a namespace: the /**/ keys still match.
    (['-r', '__ns:=/arm2', '--params-file', str(PARAMS)],
     {'noise_std': 0.02, 'seed': 1, 'sample_period': 0.01, 'initial_angles': None}),
    # -p after the file wins over it.
    (['-r', '__ns:=/arm3', '--params-file', str(PARAMS), '-p', 'noise_std:=0.05'],
     {'noise_std': 0.05, 'seed': 1, 'sample_period': 0.01, 'initial_angles': None}),
    # -p before the file holds for what the file leaves out, and loses to what it lists (rcl
    # applies a /**/<node> entry after a /** entry made before it): the file's header says so.
    (['-r', '__ns:=/arm4', '-p', 'sample_period:=0.02', '-p', 'initial_angles:=[5.0]',
      '--params-file', str(PARAMS)],
     {'noise_std': 0.02, 'seed': 1, 'sample_period': 0.01, 'initial_angles': [5.0]}),
])
def test_the_file_applies_in_a_namespace_and_a_later_p_wins(arguments, expected):
    namespace = arguments[1].split(':=')[1]
    with RosHarness(args=['--ros-args', *arguments]) as ros:
        plant = ros.add(PlantNode)
        identifier = ros.add(IdentifierNode)
        assert plant.get_namespace() == namespace == identifier.get_namespace()
        got = {name: plant.parameters.value(name) for name in expected}
        if got['initial_angles'] is not None:
            got['initial_angles'] = list(got['initial_angles'])
        assert got == expected
        assert plant.last_angles == [(expected['initial_angles'] or [0.0])[0]]
        # A -p is for every node of the process, as the file's /**/ keys are.
        assert identifier.get_parameter('noise_std').value == expected['noise_std']
        assert identifier.get_parameter('publish_period').value == 0.1

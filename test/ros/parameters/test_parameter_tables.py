"""
One table per node: the nodes declare what it says, check by it, and the docs are written from it.

The parameter tables of docs/interfaces.md section 3 and docs/guide/nodes.md and the shipped
config/hydro_sdp.yaml are checked against the tables here (the same code that writes them,
in check mode); running nodes answer for the tables over the parameter services.
"""

import math
import shutil

from conftest import REPO
from hydro_sdp.bags import write_bag
from hydro_sdp.core.errors import ConfigurationError
from hydro_sdp.core.model.records import Record
from hydro_sdp.ros.bag_player import BagPlayerNode
from hydro_sdp.ros.bag_recorder import BagRecorderNode
from hydro_sdp.ros.controller_node import PipControllerNode
from hydro_sdp.ros.identifier_node import IdentifierNode
from hydro_sdp.ros.parameters import documents
from hydro_sdp.ros.parameters.descriptors import ROS_TYPES
from hydro_sdp.ros.parameters.node_parameters import NodeParameters
from hydro_sdp.ros.parameters.spec import ParameterSpec, ParameterTable
from hydro_sdp.ros.plant_node import PlantNode
from hydro_sdp.ros.testing import ParameterClient, RosHarness
import numpy as np
import pytest
from rclpy.node import Node
from rclpy.parameter import Parameter

pytestmark = pytest.mark.ros

NODES = {'plant_node': PlantNode, 'controller_node': PipControllerNode,
         'identifier_node': IdentifierNode, 'bag_recorder': BagRecorderNode,
         'bag_player': BagPlayerNode}


def test_the_docs_and_the_params_file_are_written_from_the_tables():
    stale = documents.stale_files(REPO)
    assert stale == [], ('regenerate with python -m hydro_sdp.ros.parameters.documents '
                         f'--write: {stale}')
    executables = [table.executable for table in documents.TABLES]
    for path, style in zip(documents.MARKDOWN_FILES, ('reference', 'guide')):
        assert documents.blocks((REPO / path).read_text()) == \
            [(style, executable) for executable in executables], path


def test_an_edited_table_in_the_docs_is_found_and_rewritten(tmp_path):
    for path in (*documents.MARKDOWN_FILES, documents.PARAMS_FILE):
        (tmp_path / path).parent.mkdir(parents=True, exist_ok=True)
        shutil.copy(REPO / path, tmp_path / path)
    interfaces = tmp_path / documents.MARKDOWN_FILES[0]
    text = interfaces.read_text()
    edited = text.replace('| `feedback_timeout` | double | `0.5` |',
                          '| `feedback_timeout` | double | `0.3` |')
    assert edited != text
    interfaces.write_text(edited)
    params = tmp_path / documents.PARAMS_FILE
    params.write_text(params.read_text().replace('feedback_timeout: 0.5', 'feedback_timeout: 1'))
    assert documents.stale_files(tmp_path) == [interfaces, params]
    assert documents.main(['--root', str(tmp_path)]) == 1
    assert documents.main(['--root', str(tmp_path), '--write']) == 0
    assert interfaces.read_text() == text and documents.stale_files(tmp_path) == []


@pytest.fixture(scope='module')
def nodes(tmp_path_factory):
    """Run one node of each executable (the controller with one joint) in one harness."""
    folder = tmp_path_factory.mktemp('tables')
    t = np.arange(1, 21) * 0.01
    bag = write_bag(folder / 'played', [Record(t=t, v=np.zeros(20), y=np.zeros(20),
                                               joint='j2')])
    given = {'bag_recorder': {'output': str(folder / 'recorded')},
             'bag_player': {'bag': str(bag), 'autostart': False}}
    with RosHarness() as ros:
        nodes = {executable: ros.add(cls, parameters=given.get(executable))
                 for executable, cls in NODES.items()}
        yield {**nodes, 'harness': ros}


@pytest.mark.parametrize('table', documents.TABLES, ids=lambda table: table.executable)
def test_every_node_answers_for_its_table_over_the_services(nodes, table):
    # What ros2 param list/get/set sees: every name of the table and no other, its default,
    # a write to a read-only one refused, a value past a range refused and the value kept.
    node = nodes[table.executable]
    client = ParameterClient(nodes['harness'], node.get_name())
    declared = set(node.list_parameters([], 0).names) - {'use_sim_time',
                                                         'start_type_description_service'}
    joints = getattr(node, 'joints', [])
    expected = set()
    for spec in table.specs:
        names = [f'{joint}.{spec.name}' for joint in joints] + [spec.name] if spec.per_joint \
            else [spec.name]
        for name in [name for name in names if node.has_parameter(name)]:
            expected.add(name)
            key = name.replace('.', '__')
            answer = client.get(name)
            if not answer:  # declared without a value (an optional array): rclpy's answer
                assert spec.default is None and spec.is_array, name
                continue
            [(kind, value)] = answer
            assert kind == ROS_TYPES[spec.kind], name
            if spec.default is not None and name not in ('autostart', 'bag', 'output'):
                assert value == pytest.approx(spec.default), name
            if spec.read_only:
                [result] = client.set_each(**{key: value})
                assert not result.successful and 'read-only' in result.reason, name
            elif spec.low is not None:
                beyond = spec.high + (spec.high - spec.low) + 1
                [result] = client.set_each(**{key: int(beyond) if spec.kind == 'int'
                                              else float(beyond)})
                assert not result.successful, name
                assert client.get(name) == [(kind, value)], name
        assert names and any(node.has_parameter(name) for name in names) or spec.on_demand \
            or spec.per_joint, spec.name
    assert declared == expected


def test_the_controller_declares_its_joints_per_joint():
    with RosHarness() as ros:
        models = [str(REPO / 'config' / f'lucie_{joint}.yaml') for joint in ('boom', 'dipper')]
        controller = ros.add(PipControllerNode, parameters={'joints': ['boom', 'dipper'],
                                                            'model_files': models})
        for spec in documents.CONTROLLER_PARAMETERS.joint_specs:
            assert not controller.has_parameter(spec.name)
            for joint in ('boom', 'dipper'):
                description = controller.describe_parameter(f'{joint}.{spec.name}').description
                assert description == f'{joint}: {spec.documented}'


@pytest.mark.parametrize('name, value, message', [
    ('idz.mode', 'fast', "must be one of zero, smooth, hysteresis, got 'fast'"),
    ('idz.dead_zone', [-1.0, 0.0, 1.0], 'needs two numbers'),
    ('idz.dead_zone', [-1.0, math.nan], 'must be finite'),
    ('gains.f', [math.inf], 'must be finite'),
    ('j2.gains.k_i', 11.0, 'out of range'),
])
def test_a_value_that_breaks_the_table_is_refused_naming_the_parameter(
        nodes, name, value, message):
    controller = nodes['controller_node']
    before = controller.spec
    result = controller.set_parameters([Parameter(name, value=value)])[0]
    assert not result.successful and message in result.reason
    assert controller.spec == before


def test_a_value_too_large_is_refused_on_its_size_before_it_is_read(nodes):
    controller = nodes['controller_node']
    before = controller.spec
    huge = [0.1] * 10**5
    # Over the services, answered from the message: the other value of a one-by-one request
    # is set on its own; an atomic request is refused whole.
    client = ParameterClient(nodes['harness'], 'pip_controller')
    first, second = client.set_each(gains__f=huge, idz__beta=before.idz.beta)
    assert not first.successful and second.successful
    assert first.reason == "parameter 'gains.f' takes at most 64 values, got 100000"
    result = client.set_atomically(gains__f=huge, idz__beta=0.06)
    assert not result.successful and 'at most 64 values' in result.reason
    # More names than a node has parameters: a reading service answers nothing.
    assert client.get('idz.beta') == [(Parameter.Type.DOUBLE, before.idz.beta)]
    assert client.get(*['idz.beta'] * 2000) == []
    assert client.get('x' * 5000) == []
    # In the process, refused by the pre-set callback, a string as an array.
    result = controller.set_parameters([Parameter('idz.mode', value='x' * 5000)])[0]
    assert result.reason == "parameter 'idz.mode' takes at most 4096 characters, got 5000"
    assert not controller.set_parameters([Parameter('gains.g', value=huge)])[0].successful
    assert controller.spec == before and controller.get_parameter('idz.beta').value == \
        before.idz.beta


def test_use_sim_time_is_fixed_once_a_node_runs(nodes):
    for executable in ('plant_node', 'controller_node', 'bag_recorder'):
        node = nodes[executable]
        result = node.set_parameters([Parameter('use_sim_time', value=False)])[0]
        assert not result.successful, executable
        assert result.reason.startswith('use_sim_time is fixed at start-up (it is true)')
        assert node.get_clock().ros_time_is_active
        assert node.set_parameters([Parameter('use_sim_time', value=True)])[0].successful


def test_a_start_up_value_that_breaks_the_table_stops_the_node():
    from rclpy.exceptions import ParameterException
    with RosHarness() as ros:
        with pytest.raises(ParameterException, match='needs two numbers'):
            ros.add(PlantNode, parameters={'dead_zone_shift': [0.1, 0.2, 0.3]})
        with pytest.raises(ParameterException, match='must be one of sqlite3'):
            ros.add(BagRecorderNode, parameters={'output': 'x', 'storage': 'mcap'})
        with pytest.raises(ConfigurationError, match="'bag' is required"):
            ros.add(BagPlayerNode)


def test_a_writable_parameter_without_an_effect_is_refused_when_the_node_is_built():
    table = ParameterTable('demo', 'demo', (
        ParameterSpec('gain', 'double', 'a gain', default=1.0),
        ParameterSpec('period', 'double', 'a period', default=1.0, read_only=True)))
    with RosHarness() as ros:
        node = ros.add(Node, node_name='demo')
        with pytest.raises(ValueError, match="handlers differ: \\['gain'\\]"):
            NodeParameters(node, table)
        NodeParameters(node, table, apply={'gain': lambda: None}).declare()
        assert node.get_parameter('gain').value == 1.0


@pytest.mark.parametrize('spec', [
    {'name': 'a', 'kind': 'string', 'description': 'x', 'default': '', 'low': 0.0, 'high': 1.0},
    {'name': 'a', 'kind': 'double', 'description': 'x', 'default': 1.0, 'choices': ('b',)},
    {'name': 'a', 'kind': 'double', 'description': 'x', 'default': 5.0, 'low': 0.0, 'high': 1.0},
    {'name': 'a', 'kind': 'double', 'description': 'x'},
    {'name': 'a', 'kind': 'double_array', 'description': 'x', 'default': (1.0,), 'length': 2},
])
def test_a_spec_that_contradicts_itself_is_refused(spec):
    with pytest.raises((ValueError, ConfigurationError)):
        ParameterSpec(**spec)

"""The shipped SROS2 policy allows each node what it uses, and the valve to the controller only."""

from fnmatch import fnmatch
import xml.etree.ElementTree as ElementTree

from conftest import REPO
from hydro_sdp.ros.bag_recorder import BagRecorderNode
from hydro_sdp.ros.controller_node import PipControllerNode
from hydro_sdp.ros.identifier_node import IdentifierNode
from hydro_sdp.ros.plant_node import PlantNode
from hydro_sdp.ros.testing import RosHarness
import pytest

pytestmark = pytest.mark.ros

POLICY = REPO / 'config' / 'hydro_sdp.policy.xml'
#: What each kind of endpoint needs in a profile: the element and its attribute.
RIGHTS = {'publish': ('topics', 'publish'), 'subscribe': ('topics', 'subscribe'),
          'reply': ('services', 'reply'), 'request': ('services', 'request')}


def _allowed(policy):
    """Return ``{context: {right: [absolute name patterns]}}`` from a policy file."""
    found = {}
    for context in policy.getroot().iter('context'):
        rights = found.setdefault(context.get('path'), {right: [] for right in RIGHTS})
        for profile in context.iter('profile'):
            namespace, node = profile.get('ns').rstrip('/'), profile.get('node')
            for right, (kind, attribute) in RIGHTS.items():
                for group in profile.iter(kind):
                    if group.get(attribute) == 'ALLOW':
                        for element in group:
                            name = element.text.strip()
                            rights[right].append(
                                name if name.startswith('/') else
                                f'{namespace}/{node}/{name[1:]}' if name.startswith('~') else
                                f'{namespace}/{name}')
    return found


@pytest.fixture(scope='module')
def used(tmp_path_factory):
    """Return what each node publishes, subscribes, serves and calls, by its context."""
    folder = tmp_path_factory.mktemp('policy')
    with RosHarness() as ros:
        nodes = {'/hydro_sdp/plant': ros.add(PlantNode, sim_time=False),
                 '/hydro_sdp/controller': ros.add(PipControllerNode, sim_time=False),
                 '/hydro_sdp/identifier': ros.add(IdentifierNode, sim_time=False),
                 '/hydro_sdp/recorder': ros.add(BagRecorderNode, sim_time=False, parameters={
                     'output': str(folder / 'bag')})}
        ros.spin_for(0.5)
        endpoints = {}
        for context, node in nodes.items():
            name, namespace = node.get_name(), node.get_namespace()
            endpoints[context] = {right: sorted(topic for topic, _ in query(name, namespace))
                                  for right, query in (
                ('publish', node.get_publisher_names_and_types_by_node),
                ('subscribe', node.get_subscriber_names_and_types_by_node),
                ('reply', node.get_service_names_and_types_by_node),
                ('request', node.get_client_names_and_types_by_node))}
        yield endpoints


def test_the_policy_allows_every_node_what_it_uses(used):
    allowed = _allowed(ElementTree.parse(POLICY))
    for context, rights in used.items():
        for right, names in rights.items():
            denied = [name for name in names
                      if not any(fnmatch(name, pattern) for pattern in allowed[context][right])]
            assert not denied, f'{context} may not {right} {denied}'
    assert '/j2/valve_command' in used['/hydro_sdp/controller']['publish']


def test_only_the_controller_may_command_the_valve_and_only_people_change_it():
    allowed = _allowed(ElementTree.parse(POLICY))

    def who(right, name):
        return sorted(context for context, rights in allowed.items()
                      if any(fnmatch(name, pattern) for pattern in rights[right]))
    assert who('publish', '/j2/valve_command') == ['/hydro_sdp/controller']
    assert who('publish', '/joint_states') == ['/hydro_sdp/plant']
    assert who('publish', '/j2/setpoint') == ['/hydro_sdp/operator']
    assert who('request', '/pip_controller/set_parameters_atomically') == [
        '/hydro_sdp/engineer', '/hydro_sdp/identifier']
    assert who('request', '/pip_controller/change_state') == ['/hydro_sdp/engineer']
    assert who('request', '/hydro_plant/set_parameters') == ['/hydro_sdp/engineer']

"""
The shipped params file, as ``ros2 run`` users load it: in a namespace, and under ``-p``.

Nodes run as separate processes; an outside rclpy client reads their parameters through
each node's ``get_parameters`` service, as ``ros2 param get`` does.
"""

import os
from pathlib import Path
import shutil
import subprocess
import sys
import time

from conftest import REPO
import pytest
import rclpy
import yaml

pytestmark = [pytest.mark.ros, pytest.mark.slow]

PARAMS = REPO / 'config' / 'hydro_sdp.yaml'
# The defaults in the code (plant_node.py, identifier_node.py) that the file changes.
PLANT_DEFAULTS = {'noise_std': 0.0, 'seed': 0, 'sample_period': 0.01}
IDENTIFIER_DEFAULTS = {'noise_std': 0.03}


def _script(name):
    found = shutil.which(name, path=str(Path(sys.executable).parent))
    if found is None:
        pytest.skip('the console scripts are not installed in this environment')
    return found


def test_the_file_uses_wildcard_keys_and_lists_only_what_differs_from_the_defaults():
    document = yaml.safe_load(PARAMS.read_text())
    assert sorted(document) == ['/**/hydro_plant', '/**/sdp_identifier']
    plant = document['/**/hydro_plant']['ros__parameters']
    identifier = document['/**/sdp_identifier']['ros__parameters']
    assert plant == {'noise_std': 0.02, 'seed': 1}
    assert identifier == {'noise_std': 0.02}
    assert all(PLANT_DEFAULTS[name] != value for name, value in plant.items())
    assert all(IDENTIFIER_DEFAULTS[name] != value for name, value in identifier.items())


@pytest.fixture
def outside(monkeypatch):
    """Return (domain, node, executor) of an outside client on a fresh domain."""
    from rclpy.context import Context
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.node import Node
    domain = 100 + (os.getpid() + 31) % 100
    monkeypatch.setenv('ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST')
    context = Context()
    rclpy.init(context=context, domain_id=domain)
    node = Node('param_client', context=context)
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(node)
    yield domain, node, executor
    executor.shutdown()
    node.destroy_node()
    rclpy.try_shutdown(context=context)


def _get(node, executor, full_name, names):
    from rcl_interfaces.srv import GetParameters
    from rclpy.parameter import parameter_value_to_python
    client = node.create_client(GetParameters, f'{full_name}/get_parameters')
    try:
        assert client.wait_for_service(timeout_sec=60.0), f'no {full_name}/get_parameters'
        future = client.call_async(GetParameters.Request(names=list(names)))
        executor.spin_until_future_complete(future, timeout_sec=30.0)
        assert future.done(), f'{full_name}/get_parameters did not answer'
        return dict(zip(names, (parameter_value_to_python(v) for v in future.result().values)))
    finally:
        node.destroy_client(client)


def test_the_file_applies_in_a_namespace_and_a_later_p_wins(outside):
    domain, node, executor = outside
    environment = dict(os.environ, ROS_DOMAIN_ID=str(domain))
    params = ['--params-file', str(PARAMS)]
    commands = {
        '/arm2/hydro_plant': ['plant_node', '-r', '__ns:=/arm2', *params],
        '/arm2/sdp_identifier': ['identifier_node', '-r', '__ns:=/arm2', *params],
        # -p after the file overrides the file's noise_std.
        '/arm3/hydro_plant': ['plant_node', '-r', '__ns:=/arm3', *params,
                              '-p', 'noise_std:=0.05'],
        # -p before the file holds for what the file leaves out (every default). (rcl applies
        # a /**/<node> entry after a /** entry created before it, so for a parameter that
        # the file does list, -p must come after the file.)
        '/arm4/hydro_plant': ['plant_node', '-r', '__ns:=/arm4', '-p', 'sample_period:=0.02',
                              *params],
    }
    processes = [subprocess.Popen([_script(name), '--ros-args', *arguments],
                                  env=environment, stdout=subprocess.DEVNULL,
                                  stderr=subprocess.PIPE, text=True)
                 for name, *arguments in commands.values()]
    try:
        assert _get(node, executor, '/arm2/hydro_plant', ['noise_std', 'seed', 'sample_period']) \
            == {'noise_std': 0.02, 'seed': 1, 'sample_period': 0.01}
        assert _get(node, executor, '/arm2/sdp_identifier', ['noise_std', 'publish_period']) \
            == {'noise_std': 0.02, 'publish_period': 0.1}
        assert _get(node, executor, '/arm3/hydro_plant', ['noise_std', 'seed', 'sample_period']) \
            == {'noise_std': 0.05, 'seed': 1, 'sample_period': 0.01}
        assert _get(node, executor, '/arm4/hydro_plant', ['noise_std', 'seed', 'sample_period']) \
            == {'noise_std': 0.02, 'seed': 1, 'sample_period': 0.02}
        time.sleep(0.1)
        for process in processes:
            assert process.poll() is None, process.stderr.read()
    finally:
        for process in processes:
            process.terminate()
        for process in processes:
            try:
                process.wait(timeout=10)
            except subprocess.TimeoutExpired:
                process.kill()
                process.wait(timeout=10)

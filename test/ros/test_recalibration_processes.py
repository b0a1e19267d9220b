"""
Recalibration after wear with the nodes as separate processes, as the README runs them.

``plant_node``, ``controller_node`` and ``identifier_node`` run as three processes with the
shipped ``config/hydro_sdp.yaml`` (noise 0.02 deg) in a fresh ROS domain; an outside client
stands in for ``ros2 topic pub`` and ``ros2 param``: it holds set-points that take the joint
across the dead-zone (as :func:`hydro_sdp.ros.scenarios.wear_and_recalibration` does), wears
the valve through the plant's ``dead_zone_shift`` parameter, and reads the controller's
``idz.dead_zone`` back over its parameter service. The plant runs in real time.
"""

import math
import os
from pathlib import Path
import random
import shutil
import subprocess
import sys
import time

from hydro_sdp.files import default_model_path, load_model
from hydro_sdp.ros import qos
import pytest
from rcl_interfaces.srv import GetParameters, SetParametersAtomically
import rclpy
from rclpy.parameter import Parameter, parameter_value_to_python
from std_msgs.msg import Bool, Float64

pytestmark = [pytest.mark.ros, pytest.mark.slow]

REPO = Path(__file__).resolve().parents[2]
PARAMS = str(REPO / 'config' / 'hydro_sdp.yaml')
SHIFT = (0.3, -0.3)                               # V, the README's wear
LEVELS = (20.0, 35.0, 15.0, 30.0)                 # deg, held in turn
HOLD = 4.0                                        # s per set-point
LIMIT = 60.0                                      # s from the wear to the recalibration


def _edges():
    return load_model(default_model_path()).static_map.dead_zone


def _script(name):
    found = shutil.which(name, path=str(Path(sys.executable).parent))
    if found is None:
        pytest.skip('the console scripts are not installed in this environment')
    return found


class _Machine:
    """The three node processes and an outside client on one fresh domain."""

    def __init__(self, *identifier_arguments):
        from rclpy.context import Context
        from rclpy.executors import SingleThreadedExecutor
        from rclpy.node import Node
        domain = random.randint(1, 200)
        environment = dict(os.environ, ROS_DOMAIN_ID=str(domain),
                           ROS_AUTOMATIC_DISCOVERY_RANGE='LOCALHOST')
        commands = {'plant_node': ['-p', 'noise_std:=0.02'], 'controller_node': [],
                    'identifier_node': list(identifier_arguments)}
        self.processes = {name: subprocess.Popen(
            [_script(name), '--ros-args', '--params-file', PARAMS, *arguments],
            env=environment, cwd=REPO, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
            text=True) for name, arguments in commands.items()}
        self.context = Context()
        rclpy.init(context=self.context, domain_id=domain)
        self.node = Node('recalibration_client', context=self.context)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)
        self.flags = []
        self.node.create_subscription(Bool, 'j2/sdp/recalibration_needed',
                                      lambda m: self.flags.append(m.data), qos.ESTIMATE_QOS)
        self.estimates = []
        self.node.create_subscription(Float64, 'j2/sdp/dead_zone_lower',
                                      lambda m: self.estimates.append(time.monotonic()),
                                      qos.ESTIMATE_QOS)
        self.setpoints = self.node.create_publisher(Float64, 'j2/setpoint', qos.COMMAND_QOS)
        self.clients = {
            (node, kind): self.node.create_client(service, f'/{node}/{kind}')
            for node in ('hydro_plant', 'pip_controller', 'sdp_identifier')
            for kind, service in (('get_parameters', GetParameters),
                                  ('set_parameters_atomically', SetParametersAtomically))}
        for client in self.clients.values():
            assert client.wait_for_service(timeout_sec=30.0), self._died()
        assert self.spin_until(lambda: self.setpoints.get_subscription_count() >= 1,
                               10.0), self._died()

    def _died(self):
        return 'the nodes did not come up: ' + '; '.join(
            f'{name}: {process.stderr.read()}' for name, process in self.processes.items()
            if process.poll() is not None)

    def spin_until(self, predicate, timeout):
        deadline = time.monotonic() + timeout
        while not predicate():
            if time.monotonic() > deadline:
                return False
            self.executor.spin_once(timeout_sec=0.01)
        return True

    def _call(self, key, request):
        future = self.clients[key].call_async(request)
        assert self.spin_until(future.done, 10.0), f'no answer from {key}'
        return future.result()

    def set_atomically(self, node, **values):
        """Set parameters of ``node`` atomically (dots written as ``__``); return the result."""
        request = SetParametersAtomically.Request(parameters=[
            Parameter(name.replace('__', '.'), value=value).to_parameter_msg()
            for name, value in values.items()])
        return self._call((node, 'set_parameters_atomically'), request).result

    def get(self, node, name):
        answer = self._call((node, 'get_parameters'), GetParameters.Request(names=[name]))
        return parameter_value_to_python(answer.values[0])

    def controller_edges(self):
        return tuple(self.get('pip_controller', 'idz.dead_zone'))

    def hold(self, hold, until=lambda: False):
        """Send the set-point of hold number ``hold`` and keep it ``HOLD`` s (or until)."""
        self.setpoints.publish(Float64(data=math.radians(LEVELS[hold % len(LEVELS)])))
        return self.spin_until(until, HOLD)

    def close(self):
        alive = {name: process.poll() is None for name, process in self.processes.items()}
        for process in self.processes.values():
            process.terminate()
        for process in self.processes.values():
            try:
                process.wait(timeout=10)
            except subprocess.TimeoutExpired:
                process.kill()
                process.wait(timeout=10)
        self.executor.shutdown()
        self.node.destroy_node()
        rclpy.try_shutdown(context=self.context)
        assert all(alive.values()), f'a node died: {alive}'


@pytest.fixture
def machine(monkeypatch):
    """Start the three processes and a client; stop them after the test."""
    monkeypatch.setenv('ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST')
    machines = []

    def start(*identifier_arguments):
        machines.append(_Machine(*identifier_arguments))
        return machines[-1]
    yield start
    for started in machines:
        started.close()


def _drive_until_recalibrated(machine, first_hold, limit):
    """Hold set-points until the controller's edges are near the worn ones; return the time."""
    worn = tuple(e + s for e, s in zip(_edges(), SHIFT))
    start = time.monotonic()
    hold = first_hold
    moved = None
    while time.monotonic() - start < limit:
        end = time.monotonic() + HOLD
        machine.setpoints.publish(Float64(data=math.radians(LEVELS[hold % len(LEVELS)])))
        while time.monotonic() < end:
            machine.spin_until(lambda: False, 0.5)
            edges = machine.controller_edges()
            if moved is None and edges != _edges():
                moved = time.monotonic() - start
            if all(abs(e - w) < 0.1 for e, w in zip(edges, worn)):
                return moved, edges
        hold += 1
    return moved, machine.controller_edges()


def test_wear_is_recalibrated_within_a_minute_at_the_readme_noise(machine):
    running = machine('-p', 'auto_recalibrate:=true')
    assert running.get('sdp_identifier', 'noise_std') == 0.02        # from the shipped file
    assert running.get('hydro_plant', 'noise_std') == 0.02
    assert running.controller_edges() == _edges()
    for hold in range(2):                       # the identifier sees the joint before wear
        running.hold(hold)
    assert running.estimates, 'the identifier published nothing'
    assert running.controller_edges() == _edges()                     # nothing to correct
    assert running.set_atomically('hydro_plant', dead_zone_shift=list(SHIFT)).successful
    moved, edges = _drive_until_recalibrated(running, 2, LIMIT)
    worn = tuple(e + s for e, s in zip(_edges(), SHIFT))
    assert moved is not None and moved < LIMIT, f'edges still {edges}'
    # Both edges moved most of the way to the worn valve's (0.3 V each).
    assert abs(edges[0] - worn[0]) < 0.1 and abs(edges[1] - worn[1]) < 0.1, edges
    assert True in running.flags


def test_identifier_parameters_apply_at_run_time_over_the_services(machine):
    running = machine()                          # auto_recalibrate false: the default
    running.hold(0)
    # publish_period: 0.1 s (default), then 0.5 s.
    count = len(running.estimates)
    running.spin_until(lambda: False, 2.0)
    assert 15 <= len(running.estimates) - count <= 25
    assert running.set_atomically('sdp_identifier', publish_period=0.5).successful
    running.spin_until(lambda: False, 0.6)
    count = len(running.estimates)
    running.spin_until(lambda: False, 2.0)
    assert 3 <= len(running.estimates) - count <= 5
    assert running.set_atomically('sdp_identifier', publish_period=0.1).successful
    # Wear without auto_recalibrate: the need is published, the controller left alone.
    assert running.set_atomically('hydro_plant', dead_zone_shift=list(SHIFT)).successful
    hold = 1
    while not any(running.flags) and hold < 1 + LIMIT / HOLD:
        running.hold(hold)
        hold += 1
    assert True in running.flags, 'recalibration_needed was never published true'
    assert running.controller_edges() == _edges()
    # Switched on at run time, it recalibrates at once (the need is already established).
    assert running.set_atomically('sdp_identifier', auto_recalibrate=True).successful
    changed = running.spin_until(lambda: running.controller_edges() != _edges(), 5.0)
    assert changed, 'auto_recalibrate true did not recalibrate'
    worn = tuple(e + s for e, s in zip(_edges(), SHIFT))
    edges = running.controller_edges()
    assert any(abs(e - w) < 0.1 for e, w in zip(edges, worn)), edges

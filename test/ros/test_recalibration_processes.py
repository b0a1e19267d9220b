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
from pathlib import Path
import time

from hydro_sdp.io.model_files import default_model_path, load_model
from hydro_sdp.ros import qos
from outside import node_process_fixture, Processes
import pytest
from rcl_interfaces.srv import GetParameters, SetParametersAtomically
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


class _Machine(Processes):
    """The three node processes and an outside client on one fresh domain."""

    def __init__(self, monkeypatch, *identifier_arguments):
        commands = {'plant_node': ['-p', 'noise_std:=0.02'], 'controller_node': [],
                    'identifier_node': list(identifier_arguments)}
        super().__init__(monkeypatch, *((name, ['--params-file', PARAMS, *arguments])
                                        for name, arguments in commands.items()), cwd=REPO)
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
            assert client.wait_for_service(timeout_sec=30.0), self.died()
        assert self.spin_until(lambda: self.setpoints.get_subscription_count() >= 1,
                               10.0), self.died()

    def set_atomically(self, node, **values):
        """Set parameters of ``node`` atomically (dots written as ``__``); return the result."""
        request = SetParametersAtomically.Request(parameters=[
            Parameter(name.replace('__', '.'), value=value).to_parameter_msg()
            for name, value in values.items()])
        return self.call(self.clients[node, 'set_parameters_atomically'], request,
                         attempts=3).result

    def get(self, node, name):
        answer = self.call(self.clients[node, 'get_parameters'],
                           GetParameters.Request(names=[name]), attempts=3)
        return parameter_value_to_python(answer.values[0])

    def controller_edges(self):
        return tuple(self.get('pip_controller', 'idz.dead_zone'))

    def hold(self, hold, until=lambda: False):
        """Send the set-point of hold number ``hold`` and keep it ``HOLD`` s (or until)."""
        self.setpoints.publish(Float64(data=math.radians(LEVELS[hold % len(LEVELS)])))
        return self.spin_until(until, HOLD)

    def close(self):
        alive = {name: process.poll() is None for name, process in self.processes.items()}
        super().close()
        assert all(alive.values()), f'a node died: {alive}'


@pytest.fixture
def machine(monkeypatch):
    """Start the three processes and a client; stop them after the test."""
    yield from node_process_fixture(_Machine, monkeypatch)


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

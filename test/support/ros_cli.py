"""
Stand-ins for the ``ros2`` command line, which this environment does not have.

A :class:`Scene` is one scene of a documentation block: the nodes its ``ros2 run``
lines start (the console scripts of this environment, as processes in a fresh ROS
domain found on this host) and a client node that does what ``ros2 topic pub
--once``, ``ros2 param set``/``get`` and ``ros2 lifecycle set`` do. At the end of the
scene every node must still be running, and Ctrl-C must end it with exit code 0 and
no traceback, as docs/guide/nodes.md says.
"""

from __future__ import annotations

import importlib
import os
from pathlib import Path
import signal
import subprocess
from typing import Any

from support.client_spin import spin_until
from support.domains import fresh_domain
from support.node_exit import stuck_in_the_middleware
import yaml

#: Seconds a stand-in waits for a node to answer (a service, a subscriber).
WAIT = 60.0


def message_type(name: str) -> Any:
    """Import a message or service class from ``package/msg/Name``."""
    package, kind, type_name = name.split('/')
    return getattr(importlib.import_module(f'{package}.{kind}'), type_name)


def fill(message: Any, values: Any) -> Any:
    """Set a message's fields from parsed YAML, as ``ros2 topic pub`` does."""
    if not isinstance(values, dict):
        raise ValueError(f'expected a mapping of fields, got {values!r}')
    types = message.get_fields_and_field_types()
    for name, value in values.items():
        if name not in types:
            raise ValueError(f'{type(message).__name__} has no field {name!r}')
        kind = types[name]
        if kind.startswith('sequence<') and '/' in kind:
            element = message_type(kind[len('sequence<'):-1].replace('/', '/msg/'))
            value = [fill(element(), item) for item in value]
        elif '/' in kind:
            value = fill(type(getattr(message, name))(), value)
        elif kind in ('double', 'float') or kind.startswith('sequence<double'):
            value = [float(v) for v in value] if isinstance(value, list) else float(value)
        setattr(message, name, value)
    return message


class Scene:
    """
    The node processes of one scene, in a fresh ROS domain, and a client node.

    Parameters
    ----------
    cwd : Path
        Working directory of the processes.
    bin_dir : Path
        Folder of the console scripts (``ros2 run hydro_sdp NAME`` runs ``bin_dir/NAME``).

    """

    def __init__(self, cwd: Path, bin_dir: Path) -> None:
        import rclpy
        from rclpy.context import Context
        from rclpy.executors import SingleThreadedExecutor
        from rclpy.node import Node

        self.cwd, self.bin_dir = cwd, bin_dir
        domain = fresh_domain()
        # The processes must be found on the host; in-process tests turn discovery off.
        self.environment = dict(os.environ, ROS_DOMAIN_ID=str(domain),
                                ROS_AUTOMATIC_DISCOVERY_RANGE='LOCALHOST')
        self.previous = os.environ.get('ROS_AUTOMATIC_DISCOVERY_RANGE')
        os.environ['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'
        self.processes: list[tuple[str, subprocess.Popen]] = []
        self.context = Context()
        rclpy.init(context=self.context, domain_id=domain)
        self.node = Node('docs_client', context=self.context)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)

    def spin_until(self, predicate: Any, timeout: float = WAIT) -> bool:
        """Spin the client until ``predicate()`` holds or ``timeout`` s pass; return it."""
        return spin_until(self.executor, predicate, timeout, step=0.02)

    def spin_for(self, seconds: float) -> None:
        """Spin the client for ``seconds``."""
        self.spin_until(lambda: False, seconds)

    def died(self) -> str:
        """Describe the processes that ended, with their stderr."""
        return '; '.join(f'{name} ended ({process.returncode}): {process.stderr.read()}'
                         for name, process in self.processes if process.poll() is not None)

    def start(self, executable: str, arguments: list[str]) -> None:
        """Start a node as ``ros2 run hydro_sdp EXECUTABLE ARGUMENTS`` does (in the background)."""
        process = subprocess.Popen([str(self.bin_dir / executable), *arguments],
                                   cwd=self.cwd, env=self.environment,
                                   stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
        self.processes.append((executable, process))

    def run(self, executable: str, arguments: list[str], timeout: float = 120.0) -> str:
        """Run a node that ends by itself (``bag_player``) in the scene's domain; return stdout."""
        done = subprocess.run([str(self.bin_dir / executable), *arguments], cwd=self.cwd,
                              env=self.environment, capture_output=True, text=True,
                              timeout=timeout)
        assert done.returncode == 0, f'{executable} exited {done.returncode}: {done.stderr}'
        return done.stdout + done.stderr

    def publish_once(self, topic: str, type_name: str, text: str) -> None:
        """Do what ``ros2 topic pub --once TOPIC TYPE TEXT`` does."""
        from rclpy.qos import QoSProfile

        cls = message_type(type_name)
        message = fill(cls(), yaml.safe_load(text) or {})
        publisher = self.node.create_publisher(cls, topic, QoSProfile(depth=10))
        assert self.spin_until(lambda: publisher.get_subscription_count() >= 1), \
            f'nobody subscribes to {topic}; {self.died()}'
        publisher.publish(message)
        self.spin_for(0.5)
        self.node.destroy_publisher(publisher)

    def _call(self, service_type: Any, name: str, request: Any) -> Any:
        client = self.node.create_client(service_type, name)
        try:
            assert client.wait_for_service(timeout_sec=WAIT), \
                f'no service {name}; {self.died()}'
            future = client.call_async(request)
            assert self.spin_until(future.done), f'no answer from {name}'
            return future.result()
        finally:
            self.node.destroy_client(client)

    def set_parameter(self, node: str, name: str, text: str) -> None:
        """Do what ``ros2 param set NODE NAME VALUE`` does; the node must accept it."""
        from rcl_interfaces.srv import SetParameters
        from rclpy.parameter import Parameter

        request = SetParameters.Request(
            parameters=[Parameter(name, value=yaml.safe_load(text)).to_parameter_msg()])
        result = self._call(SetParameters, f'{node}/set_parameters', request).results[0]
        assert result.successful, f'ros2 param set {node} {name} {text}: {result.reason}'

    def get_parameter(self, node: str, name: str) -> Any:
        """Do what ``ros2 param get NODE NAME`` does; return the value."""
        from rcl_interfaces.srv import GetParameters
        from rclpy.parameter import parameter_value_to_python

        answer = self._call(GetParameters, f'{node}/get_parameters',
                            GetParameters.Request(names=[name]))
        assert answer.values, f'{node} has no parameter {name}'
        return parameter_value_to_python(answer.values[0])

    def lifecycle(self, node: str, transition: str) -> None:
        """Do what ``ros2 lifecycle set NODE TRANSITION`` does; the transition must succeed."""
        from lifecycle_msgs.srv import ChangeState, GetAvailableTransitions

        available = self._call(GetAvailableTransitions, f'{node}/get_available_transitions',
                               GetAvailableTransitions.Request())
        ids = {t.transition.label: t.transition.id for t in available.available_transitions}
        assert transition in ids, f'{node} cannot {transition} now (it can {sorted(ids)})'
        request = ChangeState.Request()
        request.transition.id = ids[transition]
        assert self._call(ChangeState, f'{node}/change_state', request).success

    def nodes_up(self) -> int:
        """Return how many nodes other than the client the graph shows."""
        return len([name for name, _ in self.node.get_node_names_and_namespaces()
                    if name != self.node.get_name()])

    def close(self) -> None:
        """Check every node still runs, end each with Ctrl-C, and check it ended cleanly."""
        import rclpy

        try:
            # A user presses Ctrl-C once the nodes run: every process has its node up.
            assert self.spin_until(lambda: self.nodes_up() >= len(self.processes)), \
                f'{self.nodes_up()} of {len(self.processes)} nodes came up; {self.died()}'
            self.spin_for(1.0)
            assert not self.died(), self.died()
            for _, process in self.processes:
                process.send_signal(signal.SIGINT)
            for name, process in self.processes:
                try:
                    _, stderr = process.communicate(timeout=20)
                except subprocess.TimeoutExpired:
                    # faulthandler prints where every thread is, for the message.
                    process.send_signal(signal.SIGABRT)
                    _, stderr = process.communicate(timeout=20)
                    raise AssertionError(f'{name} did not end on Ctrl-C: {stderr}')
                if stuck_in_the_middleware(process.returncode, stderr):
                    continue
                assert process.returncode == 0 and 'Traceback' not in stderr, \
                    f'{name} ended with {process.returncode}: {stderr}'
        finally:
            for _, process in self.processes:
                if process.poll() is None:
                    process.kill()
            self.executor.shutdown()
            self.node.destroy_node()
            rclpy.try_shutdown(context=self.context)
            if self.previous is None:
                os.environ.pop('ROS_AUTOMATIC_DISCOVERY_RANGE', None)
            else:
                os.environ['ROS_AUTOMATIC_DISCOVERY_RANGE'] = self.previous

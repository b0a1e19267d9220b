"""Node processes on the host and a client node in the test's process (separate-process tests)."""

import os
from pathlib import Path
import shutil
import subprocess
import sys

from conftest import REPO
import pytest
import rclpy
from support.client_spin import spin_until
from support.domains import fresh_domain

MODELS = [str(REPO / 'config' / 'lucie_boom.yaml'), str(REPO / 'config' / 'lucie_dipper.yaml')]
ARM = ['-p', f"model_files:=[{','.join(MODELS)}]"]
CONTROLLER = ['-p', 'joints:=[boom,dipper]', *ARM]


def script(name):
    """Return the console script ``name`` of this environment, or None."""
    return shutil.which(name, path=str(Path(sys.executable).parent))


def required_script(name):
    """Return the console script ``name``; skip the test when it is not installed."""
    found = script(name)
    if found is None:
        pytest.skip('the console scripts are not installed in this environment')
    return found


class Processes:
    """Node processes in a fresh ROS domain found on this host, and a client node."""

    def __init__(self, monkeypatch, *commands, cwd=None):
        for name, _ in commands:
            required_script(name)          # skips before anything starts
        domain = fresh_domain()
        # The in-process harness turns discovery off; a process must be found on the host.
        monkeypatch.setenv('ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST')
        self.environment = dict(os.environ, ROS_DOMAIN_ID=str(domain))
        self.cwd = cwd
        self.processes = {}
        for name, arguments in commands:
            self.start(name, *arguments)
        from rclpy.context import Context
        from rclpy.executors import SingleThreadedExecutor
        from rclpy.node import Node
        self.context = Context()
        rclpy.init(context=self.context, domain_id=domain)
        self.node = Node('outside_client', context=self.context)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)

    def start(self, name, *arguments, **options):
        """Start the console script ``name`` (``options`` go to :class:`subprocess.Popen`)."""
        self.processes[name] = subprocess.Popen(
            [required_script(name), '--ros-args', *arguments], env=self.environment,
            cwd=self.cwd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
            **options)
        return self.processes[name]

    def died(self):
        """Describe the processes that ended, with their stderr."""
        return '; '.join(f'{name} ended: {process.stderr.read()}'
                         for name, process in self.processes.items()
                         if process.poll() is not None) or 'all alive'

    def spin_until(self, predicate, timeout=10.0):
        """Spin the client until ``predicate()`` holds or ``timeout`` s pass; return it."""
        return spin_until(self.executor, predicate, timeout, step=0.01)

    def spin_for(self, seconds):
        """Spin the client for ``seconds``."""
        self.spin_until(lambda: False, seconds)

    def call(self, client, request, timeout=10.0, attempts=1):
        """
        Call a service and return its answer.

        An idempotent request (parameter services) may be sent ``attempts`` times: a
        service can be discovered before the client's response reader is matched, and
        DDS then drops the first answer (as `ros2 service call` users see on busy hosts).
        """
        assert client.wait_for_service(timeout_sec=30.0), self.died()
        for _ in range(attempts):
            future = client.call_async(request)
            if self.spin_until(future.done, timeout):
                return future.result()
            client.remove_pending_request(future)
        raise AssertionError(f'no answer from the service in {attempts} tries; {self.died()}')

    def stop(self, name):
        """Stop one process with SIGTERM; return its stderr."""
        process = self.processes.pop(name)
        process.terminate()
        try:
            _, stderr = process.communicate(timeout=10)
        except subprocess.TimeoutExpired:
            process.kill()
            _, stderr = process.communicate(timeout=10)
        return stderr

    def close(self):
        """Stop every process and the client."""
        for name in list(self.processes):
            self.stop(name)
        self.executor.shutdown()
        self.node.destroy_node()
        rclpy.try_shutdown(context=self.context)


def node_process_fixture(kind, monkeypatch):
    """Yield a function starting ``kind(monkeypatch, *arguments)``; close each after the test."""
    started = []

    def start(*arguments):
        started.append(kind(monkeypatch, *arguments))
        return started[-1]
    yield start
    for client in started:
        client.close()

"""A launch-free harness to run hydro_sdp nodes in-process, deterministically (methods 9.4)."""

from __future__ import annotations

import os
import random
import time
from typing import Callable, cast, Iterable, Mapping, Protocol, TypeVar, Union

from hydro_sdp.ros.lockstep import Lockstep
from hydro_sdp.ros.parameters.spec import ParameterValue
from hydro_sdp.ros.qos import mark_in_process
from rcl_interfaces.msg import Parameter as ParameterMessage, SetParametersResult
from rcl_interfaces.srv import GetParameters, SetParameters, SetParametersAtomically
import rclpy
from rclpy.clock import ROSClock
from rclpy.context import Context
from rclpy.executors import SingleThreadedExecutor
from rclpy.lifecycle import LifecycleNode
from rclpy.node import Node
from rclpy.parameter import Parameter, parameter_value_to_python
from rclpy.publisher import Publisher
from rclpy.time import Time

__all__ = ['Lockstep', 'ParameterClient', 'RosHarness', 'TrajectoryReceiver']

# Nodes of one context still match with discovery off; nothing else on the host is seen.
os.environ.setdefault('ROS_AUTOMATIC_DISCOVERY_RANGE', 'OFF')

#: The node class a harness makes, and so the node it returns.
NodeT = TypeVar('NodeT', bound=Node)
#: The answer of one of a node's parameter services.
ParameterAnswer = Union[GetParameters.Response, SetParameters.Response,
                        SetParametersAtomically.Response]


class TrajectoryReceiver(Protocol):
    """A node that counts the trajectories it took (a controller)."""

    @property
    def trajectories_received(self) -> int:
        """Trajectories taken so far."""


def _set_clock(node: Node, nanoseconds: int) -> None:
    # A node's clock is a ROSClock (ROS time), the one that takes an override.
    cast(ROSClock, node.get_clock()).set_ros_time_override(Time(nanoseconds=nanoseconds))


class RosHarness:
    """
    A private ROS context with an executor and the nodes added to it.

    ``domain_id``: DDS domain; default: a random one, so parallel test runs do not meet.
    ``args``: command-line arguments of the context, as ``ros2 run`` passes them to every node of a
    process (``['--ros-args', '-r', '__ns:=/arm2', '--params-file', 'p.yaml']``).
    """

    def __init__(self, domain_id: int | None = None, args: list[str] | None = None) -> None:
        self.context = Context()
        rclpy.init(args=args, context=self.context,
                   domain_id=random.randint(1, 200) if domain_id is None else domain_id)
        # Its nodes' subscriptions skip the QoS event handlers: here every publisher is a
        # node of the harness. A lockstep step then checks half the handlers (12 of 24 for
        # a plant, a controller and an identifier) and costs about a sixth less.
        mark_in_process(self.context)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.nodes: list[Node] = []
        self.time_ns = 0
        #: Longest wait of one spin; short, since messages within a process arrive fast.
        self.spin_timeout = 0.001

    def add(self, node_cls: Callable[..., NodeT], *,
            parameters: Mapping[str, ParameterValue] | None = None, sim_time: bool = True,
            cli_args: list[str] | None = None, services: bool = True,
            **kwargs: object) -> NodeT:
        """
        Create a node in the harness and add it to the executor.

        ``node_cls``: a node class that forwards ``**kwargs`` to :class:`rclpy.node.Node` (its
        options, :class:`~hydro_sdp.ros.node_options.NodeOptions`).
        ``parameters``: parameter overrides by name.
        ``sim_time``: whether the node's clock is set by the harness.
        ``cli_args``: ROS command-line arguments (``--ros-args --params-file ...``).
        """
        overrides = [Parameter(name, value=value) for name, value in (parameters or {}).items()]
        if sim_time:
            overrides.append(Parameter('use_sim_time', value=True))
        if not services:
            overrides.append(Parameter('start_type_description_service', value=False))
            kwargs['start_parameter_services'] = False
        node = node_cls(context=self.context, parameter_overrides=overrides,
                        cli_args=cli_args, **kwargs)
        if sim_time:
            _set_clock(node, self.time_ns)
            if hasattr(node, 'steady_clock'):
                # The harness is the only clock: a pause of the test between steps, or of a
                # busy host, is no silence of the feedback (a watchdog would close the valve).
                node.steady_clock = lambda: self.time_ns
        self.executor.add_node(node)
        self.nodes.append(node)
        return node

    def helper(self, name: str = 'test_helper') -> Node:
        """Return a plain node (simulated time) for a test's own publishers and subscribers."""
        return self.add(Node, node_name=name, services=False)

    def set_time(self, nanoseconds: int) -> None:
        """Set the clock of every simulated-time node (timers that are due fire on spin)."""
        self.time_ns = nanoseconds
        for node in self.nodes:
            if node.get_parameter('use_sim_time').value:
                _set_clock(node, nanoseconds)

    def spin_until(self, predicate: Callable[[], bool], timeout: float = 5.0) -> bool:
        """
        Spin until ``predicate()`` holds or ``timeout`` seconds of wall time pass.

        ``timeout``: wall-clock limit, s.
        """
        deadline = time.monotonic() + timeout
        while not predicate():
            if time.monotonic() > deadline:
                return False
            self.executor.spin_once(timeout_sec=self.spin_timeout)
        return True

    def spin_for(self, seconds: float) -> None:
        """Spin for ``seconds`` of wall time."""
        deadline = time.monotonic() + seconds
        while time.monotonic() < deadline:
            self.executor.spin_once(timeout_sec=0.005)

    def transition(self, node: LifecycleNode, transition: str) -> str:
        """Run a lifecycle transition of ``node`` in this thread; return the state reached."""
        getattr(node, f'trigger_{transition}')()
        return str(node._state_machine.current_state[1])

    def send(self, publisher: Publisher, message: object, received: Callable[[], bool],
             timeout: float = 5.0) -> None:
        """Publish ``message`` and spin until ``received()`` holds (the receiver took it)."""
        publisher.publish(message)
        if not self.spin_until(received, timeout):
            raise TimeoutError(f'{type(message).__name__} on {publisher.topic_name} was not '
                               'received')

    def send_trajectory(self, publisher: Publisher, controllers: Iterable[TrajectoryReceiver],
                        names: list[str],
                        times: list[float], positions_deg: list[list[float]],
                        stamp_ns: int = 0) -> None:
        """
        Publish a ``JointTrajectory`` (angles in degrees) and wait until every controller took it.

        ``times``: time from start of each point, s.
        ``positions_deg``: one row of angles per point, degrees.
        ``stamp_ns``: header stamp, ns (0: start on arrival).
        """
        from hydro_sdp.ros.conversions import fill_trajectory
        from trajectory_msgs.msg import JointTrajectory
        targets = list(controllers)
        counts = [c.trajectories_received for c in targets]
        message = fill_trajectory(JointTrajectory(), names, times, positions_deg, stamp_ns)
        self.send(publisher, message, lambda: all(
            c.trajectories_received > n for c, n in zip(targets, counts)))

    def close(self) -> None:
        """Destroy the nodes and shut the context down."""
        self.executor.shutdown()
        for node in reversed(self.nodes):
            node.destroy_node()
        self.nodes.clear()
        rclpy.try_shutdown(context=self.context)

    def __enter__(self) -> RosHarness:
        """Return the harness."""
        return self

    def __exit__(self, *exc: object) -> None:
        """Close the harness."""
        self.close()


class ParameterClient:
    """
    A node's parameter services, called as ``ros2 param`` calls them, in a harness.

    ``node_name``: full name of the node (``/pip_controller``, or without the slash).
    """

    def __init__(self, harness: RosHarness, node_name: str) -> None:
        self.harness = harness
        name = '/' + node_name.lstrip('/')
        helper = harness.helper(f'parameter_client_{len(harness.nodes)}')
        self._clients = {kind: helper.create_client(service, f'{name}/{kind}')
                         for kind, service in (('get_parameters', GetParameters),
                                               ('set_parameters', SetParameters),
                                               ('set_parameters_atomically',
                                                SetParametersAtomically))}
        ready = harness.spin_until(lambda: all(c.service_is_ready()
                                               for c in self._clients.values()))
        if not ready:
            raise TimeoutError(f'{name} offers no parameter services')

    def _call(self, kind: str, request: object) -> ParameterAnswer:
        future = self._clients[kind].call_async(request)
        if not self.harness.spin_until(future.done):
            raise TimeoutError(f'no answer from {kind}')
        return future.result()

    @staticmethod
    def _messages(values: Mapping[str, ParameterValue]) -> list[ParameterMessage]:
        # Keyword names cannot hold dots: ``gains__k_i`` is ``gains.k_i``.
        return [Parameter(name.replace('__', '.'), value=value).to_parameter_msg()
                for name, value in values.items()]

    def set_atomically(self, **values: ParameterValue) -> SetParametersResult:
        """Set parameters in one atomic request; return its ``SetParametersResult``."""
        request = SetParametersAtomically.Request(parameters=self._messages(values))
        return self._call('set_parameters_atomically', request).result

    def set_each(self, **values: ParameterValue) -> list[SetParametersResult]:
        """Set parameters one by one; return a ``SetParametersResult`` for each."""
        request = SetParameters.Request(parameters=self._messages(values))
        return list(self._call('set_parameters', request).results)

    def get(self, *names: str) -> list[tuple[Parameter.Type, ParameterValue]]:
        """Return the type and value of each of ``names``."""
        answer = self._call('get_parameters', GetParameters.Request(names=list(names)))
        return [(Parameter.Type(value.type), parameter_value_to_python(value))
                for value in answer.values]

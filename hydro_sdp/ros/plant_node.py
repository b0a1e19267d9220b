"""
Simulated hydraulic joints as a ROS node (``ros2 run hydro_sdp plant_node``).

Topics, parameters and lifecycle: docs/interfaces.md section 3.1.

"""

from __future__ import annotations

from dataclasses import replace
from functools import partial
from typing import Unpack

from hydro_sdp.core.control.command_gate import CommandGate
from hydro_sdp.core.control.scheduling import seconds_to_ns
from hydro_sdp.core.errors import ConfigurationError, DataError
from hydro_sdp.core.model.simulation import JointSimulator
from hydro_sdp.core.model.static_maps import shifted_map, StaticMap
from hydro_sdp.core.synthetic.programs import start_angle
from hydro_sdp.io.model_files import default_model_path, load_model
from hydro_sdp.ros import conversions, qos
from hydro_sdp.ros.node_options import NodeOptions
from hydro_sdp.ros.parameters.node_parameters import NodeParameters, ParameterRequest
from hydro_sdp.ros.parameters.plant import PLANT_PARAMETERS
from hydro_sdp.ros.runner import run_node
import numpy as np
from rclpy.node import Node
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64


class PlantNode(Node):
    """One or several simulated joints publishing ``joint_states`` every ``sample_period``."""

    def __init__(self, *, node_name: str = 'hydro_plant', **kwargs: Unpack[NodeOptions]) -> None:
        super().__init__(node_name, **kwargs)
        self.parameters = NodeParameters(
            self, PLANT_PARAMETERS, check=self._check_request,
            apply={'noise_std': self._apply_noise, 'dead_zone_shift': self._apply_shift})
        self.parameters.declare(defaults={'model_file': str(default_model_path())})
        parameters = self.parameters
        self.sample_period = parameters.period('sample_period')
        self.models = [load_model(path) for path in
                       (parameters.texts('model_files') or [parameters.text('model_file')])]
        self.names = [model.joint for model in self.models]
        if len(set(self.names)) != len(self.names):
            raise ConfigurationError(f'joint names must be distinct, got {self.names}')
        seed = parameters.integer('seed')
        self._rngs = [np.random.default_rng([seed, index]) for index in range(len(self.names))]
        self._base_maps = [model.static_map for model in self.models]
        self._shift = (0.0, 0.0)
        self._noise = 0.0
        self._simulators = [JointSimulator(model, self.sample_period, angle,
                                           v_before=model.rest_command)
                            for model, angle in zip(self.models, self._initial_angles())]
        self._commands = [model.rest_command for model in self.models]
        self._gates = [CommandGate(model.input_limits,
                                   source=parameters.text('command_source'),
                                   rate_limit=parameters.double('command_rate_limit'),
                                   timeout_ns=seconds_to_ns(parameters.double('command_timeout')))
                       for model in self.models]
        self._command_topics = [self.resolve_topic_name(f'{name}/valve_command')
                                for name in self.names]
        self._silent = [False] * len(self.models)
        self._named_ns = -10**18
        self.ticks = 0
        self.commands_received = 0
        self.commands_refused = 0
        self.last_angles = [sim.angle for sim in self._simulators]
        self._state_pub = self.create_publisher(JointState, 'joint_states', qos.STATE_QOS,
                                                event_callbacks=qos.QUIET_PUBLISHER)
        self._command_subs = [
            self.create_subscription(Float64, f'{name}/valve_command',
                                     partial(self._on_command, index), qos.COMMAND_QOS,
                                     event_callbacks=qos.subscription_events(self.context))
            for index, name in enumerate(self.names)]
        parameters.start()
        self._timer = self.create_timer(self.sample_period, self._on_tick)

    def _initial_angles(self) -> list[float]:
        """Return each joint's starting angle: given, or 0, or mid-travel if 0 is beyond a stop."""
        initial = self.parameters.doubles('initial_angles')
        if initial is not None:
            if len(initial) != len(self.models):
                raise ConfigurationError(f'initial_angles needs {len(self.models)} values')
            return initial
        return [0.0 if model.angle_limits is None or
                model.angle_limits[0] < 0.0 < model.angle_limits[1] else start_angle(model)
                for model in self.models]

    def _shifted_maps(self, shift: tuple[float, float]) -> list[StaticMap]:
        return [shifted_map(base, shift) for base in self._base_maps]

    def _check_request(self, request: ParameterRequest) -> None:
        # Checks only: nothing applies before the whole request is accepted. The worn model
        # is built whole, as applying it does (edges inside the valve range...).
        shift = request.pair('dead_zone_shift', self._shift)
        for model, static_map in zip(self.models, self._shifted_maps(shift)):
            replace(model, static_map=static_map)

    def _apply_shift(self) -> None:
        request = self.parameters.current(['dead_zone_shift'])
        shift = request.pair('dead_zone_shift', self._shift)
        if shift == self._shift:
            return
        for simulator, static_map in zip(self._simulators, self._shifted_maps(shift)):
            simulator.set_static_map(static_map)
        self._shift = shift
        self.get_logger().info(f'dead-zone edges moved by {list(shift)}')

    def _apply_noise(self) -> None:
        noise = self.parameters.double('noise_std')
        if self.parameters.live and noise != self._noise:
            self.get_logger().info(f'measurement noise now {noise} deg')
        self._noise = noise

    def _command_sources(self, index: int, named: bool = False) -> list[str]:
        # The writers matched to this subscription, as the middleware counts them (no graph
        # lookup); their names from the graph only when a source is named (or for a warning),
        # one '' for each the graph does not know yet.
        count = self._command_subs[index].get_publisher_count()
        if not (named or self._gates[index].source) or count == 0:
            return [''] * count
        names = [_full_name(info.node_namespace, info.node_name)
                 for info in self.get_publishers_info_by_topic(self._command_topics[index])]
        return names + [''] * max(count - len(names), 0)

    def _on_command(self, index: int, message: Float64) -> None:
        self.commands_received += 1
        topic = self._command_topics[index]
        publishers = self._command_sources(index)
        now = self.get_clock().now().nanoseconds
        try:
            value = self._gates[index].admit(float(message.data), now, publishers)
        except DataError as error:
            self.commands_refused += 1
            self._commands[index] = self.models[index].rest_command
            if now - self._named_ns >= 1_000_000_000:       # the names, once a second
                self._named_ns = now
                publishers = [name or 'unknown' for name in self._command_sources(index, True)]
                self._warn(f'refused a command on {topic} ({error}; publishers '
                           f'{publishers}); valve closed')
            return
        if value is None:
            self.commands_refused += 1
            self._warn(f'dropped a command on {topic}: more than '
                       f'{self._gates[index].rate_limit:g} per s')
            return
        self._commands[index] = value
        self._silent[index] = False

    def _warn(self, text: str) -> None:
        self.get_logger().warning(text, throttle_duration_sec=1.0,
                                  throttle_time_source_type=self.get_clock())

    def _close_silent_valves(self) -> None:
        now = self.get_clock().now().nanoseconds
        for index, gate in enumerate(self._gates):
            if not self._silent[index] and gate.silent(now):
                self._silent[index] = True
                self._commands[index] = self.models[index].rest_command
                self._warn(f'no command on {self._command_topics[index]} for more than '
                           f'command_timeout {gate.timeout_ns * 1e-9:g} s; valve closed')

    def _on_tick(self) -> None:
        self._close_silent_valves()
        before = self.last_angles
        if self.ticks:
            angles = [sim.step(command)
                      for sim, command in zip(self._simulators, self._commands)]
        else:
            angles = [sim.angle for sim in self._simulators]
        speeds = [(now - then) / self.sample_period for now, then in zip(angles, before)]
        if self._noise > 0.0:
            measured = [a + float(rng.normal(0.0, self._noise))
                        for a, rng in zip(angles, self._rngs)]
        else:
            measured = angles
        self.last_angles = angles
        message = conversions.fill_joint_state(
            JointState(), self.get_clock().now().nanoseconds, self.names, measured, speeds)
        self._state_pub.publish(message)
        self.ticks += 1


def _full_name(namespace: str, name: str) -> str:
    return f"{namespace.rstrip('/')}/{name}"


def main(args: list[str] | None = None) -> None:
    """Run :class:`PlantNode` until shutdown (console script ``plant_node``)."""
    run_node(PlantNode, args)

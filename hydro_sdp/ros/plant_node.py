"""
Simulated hydraulic joints as a ROS node (``ros2 run hydro_sdp plant_node``).

The node owns the only timer of a simulated machine. On each tick it applies,
for every joint, the last valve command received before the tick (the command
in force over the interval that ends now: the rule of
:func:`~hydro_sdp.core.model.timing.command_in_force`, here in arrival order since a
Float64 carries no stamp), advances the core
:class:`~hydro_sdp.core.model.simulation.JointSimulator` one sample, and publishes one
``joint_states`` with every joint (REP 103: position in rad, velocity in rad/s,
the simulated motion over the last sample, without measurement noise). Angle
parameters are in degrees. With ``use_sim_time`` the tick follows ``/clock``, so
a test can run the machine in lockstep.

Two parameters change at run time, from the next tick: ``noise_std`` (a sensor
that degrades) and ``dead_zone_shift`` (a valve that wears); a request is checked
whole before either applies, and values given at start-up apply the same way. The
others shape the machine and are read-only
(:data:`~hydro_sdp.ros.parameters.plant.PLANT_PARAMETERS`).

"""

from __future__ import annotations

from functools import partial
import math
from typing import Unpack

from hydro_sdp.core.errors import ConfigurationError
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
    """
    One or several simulated joints publishing ``joint_states`` every ``sample_period``.

    Parameters
    ----------
    node_name : str
        ROS node name.
    **kwargs : NodeOptions
        Forwarded to :class:`rclpy.node.Node` (``context``, ``parameter_overrides``...).

    """

    def __init__(self, *, node_name: str = 'hydro_plant', **kwargs: Unpack[NodeOptions]) -> None:
        super().__init__(node_name, **kwargs)
        self.parameters = NodeParameters(
            self, PLANT_PARAMETERS, check=self._check_request,
            apply={'noise_std': self._apply_noise, 'dead_zone_shift': self._apply_shift})
        self.parameters.declare(defaults={'model_file': str(default_model_path())})
        parameters = self.parameters
        self.sample_period = parameters.double('sample_period')
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
        self.ticks = 0
        self.commands_received = 0
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
        # Checks only: nothing applies before the whole request is accepted.
        self._shifted_maps(request.pair('dead_zone_shift', self._shift))

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

    def _on_command(self, index: int, message: Float64) -> None:
        value = float(message.data)
        if not math.isfinite(value):
            self.get_logger().warning(f'refused a non-finite command for {self.names[index]}',
                                      throttle_duration_sec=1.0,
                                      throttle_time_source_type=self.get_clock())
            return
        limits = self.models[index].input_limits
        if limits is not None:
            value = min(max(value, limits[0]), limits[1])
        self._commands[index] = value
        self.commands_received += 1

    def _on_tick(self) -> None:
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


def main(args: list[str] | None = None) -> None:
    """Run :class:`PlantNode` until shutdown (console script ``plant_node``)."""
    run_node(PlantNode, args)

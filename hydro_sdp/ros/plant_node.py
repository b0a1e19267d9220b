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
whole before either applies. The others shape the machine and are read-only.

"""

from __future__ import annotations

from functools import partial
import math
from typing import Any

from hydro_sdp.core.errors import ConfigurationError, HydroSdpError
from hydro_sdp.core.model.simulation import JointSimulator
from hydro_sdp.core.model.static_maps import shifted_map
from hydro_sdp.core.synthetic.programs import start_angle
from hydro_sdp.io.model_files import default_model_path, load_model
from hydro_sdp.ros import conversions, qos
from hydro_sdp.ros.params import declare, pair
from hydro_sdp.ros.runner import run_node
import numpy as np
from rcl_interfaces.msg import SetParametersResult
from rclpy.node import Node
from rclpy.parameter import Parameter
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64


class PlantNode(Node):
    """
    One or several simulated joints publishing ``joint_states`` every ``sample_period``.

    Parameters
    ----------
    node_name : str
        ROS node name.
    **kwargs : Any
        Forwarded to :class:`rclpy.node.Node` (``context``, ``parameter_overrides``...).

    """

    def __init__(self, *, node_name: str = 'hydro_plant', **kwargs: Any) -> None:
        super().__init__(node_name, **kwargs)
        period = declare(self, 'sample_period', 0.01, 'plant sample period, s',
                         low=1e-4, high=1.0, read_only=True)
        model_file = declare(self, 'model_file', str(default_model_path()),
                             'model file of the simulated joint', read_only=True)
        model_files = declare(self, 'model_files', Parameter.Type.STRING_ARRAY,
                              'model files of several joints (overrides model_file)',
                              read_only=True)
        noise = declare(self, 'noise_std', 0.0,
                        'angle measurement noise (std), deg; applies from the next tick',
                        low=0.0, high=10.0)
        seed = declare(self, 'seed', 0, 'seed of the measurement noise', read_only=True)
        initial = declare(self, 'initial_angles', Parameter.Type.DOUBLE_ARRAY,
                          'starting angle of each joint, deg (default: 0, or mid-travel)',
                          read_only=True)
        declare(self, 'dead_zone_shift', [0.0, 0.0],
                'moves every dead-zone edge by [lower, upper] input units (wear, new parts)')
        self.models = [load_model(path) for path in (model_files or [model_file])]
        names = [model.joint for model in self.models]
        if len(set(names)) != len(names):
            raise ConfigurationError(f'joint names must be distinct, got {names}')
        if initial is not None and len(initial) != len(self.models):
            raise ConfigurationError(f'initial_angles needs {len(self.models)} values')
        self.names = names
        self.sample_period = period
        self._noise = noise
        self._rngs = [np.random.default_rng([seed, index]) for index in range(len(names))]
        self._base_maps = [model.static_map for model in self.models]
        self._simulators = []
        self._commands = []
        for index, model in enumerate(self.models):
            if initial is not None:
                y0 = float(initial[index])
            else:
                limits = model.angle_limits
                y0 = 0.0 if limits is None or limits[0] < 0.0 < limits[1] else start_angle(model)
            rest = model.rest_command
            self._simulators.append(JointSimulator(model, period, y0, v_before=rest))
            self._commands.append(rest)
        self.ticks = 0
        self.commands_received = 0
        self.last_angles = [sim.angle for sim in self._simulators]
        self._state_pub = self.create_publisher(JointState, 'joint_states', qos.STATE_QOS)
        self._command_subs = [
            self.create_subscription(Float64, f'{name}/valve_command',
                                     partial(self._on_command, index), qos.COMMAND_QOS)
            for index, name in enumerate(names)]
        self.add_on_set_parameters_callback(self._check_parameters)
        self.add_post_set_parameters_callback(self._apply_parameters)
        self._timer = self.create_timer(period, self._on_tick)

    def _shifted_maps(self, value: Any) -> list[Any]:
        shift = pair(value, 'dead_zone_shift')
        return [shifted_map(base, shift) for base in self._base_maps]

    def _check_parameters(self, parameters: list[Parameter]) -> SetParametersResult:
        # Checks only: nothing applies before the whole request is accepted.
        for parameter in parameters:
            if parameter.name == 'dead_zone_shift':
                try:
                    self._shifted_maps(parameter.value)
                except (HydroSdpError, TypeError) as error:
                    return SetParametersResult(successful=False, reason=str(error))
        return SetParametersResult(successful=True)

    def _apply_parameters(self, parameters: list[Parameter]) -> None:
        for parameter in parameters:
            if parameter.name == 'dead_zone_shift':
                for simulator, static_map in zip(self._simulators,
                                                 self._shifted_maps(parameter.value)):
                    simulator.set_static_map(static_map)
                self.get_logger().info(f'dead-zone edges moved by {list(parameter.value)}')
            elif parameter.name == 'noise_std':
                self._noise = float(parameter.value)
                self.get_logger().info(f'measurement noise now {self._noise} deg')

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

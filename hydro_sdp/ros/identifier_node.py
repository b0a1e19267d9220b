"""
Online identification as a ROS node (``ros2 run hydro_sdp identifier_node``).

Pairs each ``joint_states`` sample of its joint with the last valve command
received before it (the command in force over the interval that ends at the
sample, as in a recorded bag), feeds the core
:class:`~hydro_sdp.core.online.OnlineSdpIdentifier`, and publishes the estimates
and their standard deviations on ``<joint>/sdp/...``. When they are confident
and differ significantly from the IDZ the controller uses, it raises
``<joint>/sdp/recalibration_needed``; with ``auto_recalibrate`` it sets the
controller's ``idz.dead_zone`` and ``idz.slopes`` parameters itself.

"""

from __future__ import annotations

from dataclasses import replace
import math
from typing import Any

from hydro_sdp.core.controller_spec import idz_for_model
from hydro_sdp.core.errors import DataError, HydroSdpError
from hydro_sdp.core.online import OnlineSdpIdentifier, OnlineSettings
from hydro_sdp.files import default_model_path, load_model
from hydro_sdp.ros import conversions, qos
from hydro_sdp.ros.params import declare
from hydro_sdp.ros.runner import run_node
from rcl_interfaces.msg import Parameter as ParameterMessage, ParameterType, ParameterValue
from rcl_interfaces.srv import SetParametersAtomically
from rclpy.event_handler import PublisherEventCallbacks
from rclpy.node import Node
from sensor_msgs.msg import JointState
from std_msgs.msg import Bool, Float64

ESTIMATES = ('dead_zone_lower', 'dead_zone_upper', 'saturation_negative', 'saturation_positive',
             'curvature_negative', 'curvature_positive')


class IdentifierNode(Node):
    """
    Online SDP identifier of one joint, with optional automatic IDZ recalibration.

    Parameters
    ----------
    node_name : str
        ROS node name.
    **kwargs : Any
        Forwarded to :class:`rclpy.node.Node` (``context``, ``parameter_overrides``...).

    """

    def __init__(self, *, node_name: str = 'sdp_identifier', **kwargs: Any) -> None:
        super().__init__(node_name, **kwargs)
        model_file = declare(self, 'model_file', str(default_model_path()),
                             'model file to start from (kind sdp)', read_only=True)
        self.model = load_model(model_file)
        self.joint = declare(self, 'joint', self.model.joint, 'joint name in JointState',
                             read_only=True)
        self.sample_period = declare(self, 'sample_period', 0.01,
                                     'sample period of joint_states, s', low=1e-4, high=1.0,
                                     read_only=True)
        noise = declare(self, 'noise_std', 0.03, 'angle measurement noise, deg',
                        low=1e-6, high=10.0, read_only=True)
        limits = self.model.input_limits
        scale = max(abs(limits[0]), abs(limits[1])) / 10.0 if limits else 1.0
        self.publish_period = declare(self, 'publish_period', 0.1,
                                      'time between published estimates, s', low=1e-3,
                                      high=60.0)
        self.auto_recalibrate = declare(self, 'auto_recalibrate', False,
                                        'set the controller IDZ when the estimates call for it')
        self.controller_name = declare(self, 'controller_node', 'pip_controller',
                                       'controller node whose IDZ is recalibrated',
                                       read_only=True)
        self.control_period = declare(self, 'control_period', 0.05,
                                      'control period of that controller, s', low=1e-3,
                                      high=10.0, read_only=True)
        self.min_change = declare(self, 'min_change', 0.03 * scale,
                                  'smallest edge change worth a recalibration, input units',
                                  low=0.0, high=1e6)
        self.confidence = declare(self, 'confidence', 0.02 * scale,
                                  'largest edge standard deviation to act on, input units',
                                  low=0.0, high=1e6)
        self.cooldown = declare(self, 'cooldown', 5.0, 'least time between recalibrations, s',
                                low=0.0, high=3600.0)
        self.estimator = OnlineSdpIdentifier(
            self.model, self.sample_period, OnlineSettings(noise_std=noise, kappa=0.05 * scale,
                                                           change_gate=0.5 * scale,
                                                           input_scale=scale))
        self.reference = self.model.dead_zone      # the IDZ edges the controller uses
        self.samples = 0
        self.commands_received = 0
        self.recalibrations = 0
        self._command: float | None = None
        self._next_publish: int | None = None
        self._last_recalibration: int | None = None
        self._pending = None
        base = f'{self.joint}/sdp/'
        # Fifteen estimate topics: skip their QoS event handlers, which cost every wait.
        quiet = PublisherEventCallbacks(use_default_callbacks=False)
        names = ESTIMATES + tuple(f'{e}_std' for e in ESTIMATES) + (
            'delay', 'slope_negative', 'slope_positive')
        self._estimate_pubs = {
            name: self.create_publisher(Float64, base + name, qos.ESTIMATE_QOS,
                                        event_callbacks=quiet)
            for name in names}
        self._flag_pub = self.create_publisher(Bool, base + 'recalibration_needed',
                                               qos.ESTIMATE_QOS)
        self._state_sub = self.create_subscription(JointState, 'joint_states', self._on_state,
                                                   qos.STATE_QOS)
        self._command_sub = self.create_subscription(Float64, f'{self.joint}/valve_command',
                                                     self._on_command, qos.COMMAND_QOS)
        self._client = self.create_client(SetParametersAtomically,
                                          f'{self.controller_name}/set_parameters_atomically')

    def _on_command(self, message: Float64) -> None:
        if math.isfinite(message.data):
            self._command = float(message.data)
            self.commands_received += 1

    def _on_state(self, message: JointState) -> None:
        try:
            stamp, angle = conversions.joint_angle(message, self.joint)
        except DataError as error:
            self.get_logger().warning(f'skipped a sample: {error}', throttle_duration_sec=5.0,
                                      throttle_time_source_type=self.get_clock())
            return
        self.samples += 1
        if self._command is None:
            return
        self.estimator.update(self._command, angle)
        if self._next_publish is None:
            self._next_publish = stamp
        if stamp >= self._next_publish:
            self._next_publish = stamp + int(self.publish_period * 1e9)
            self._publish(stamp)

    def needs_recalibration(self) -> bool:
        """Whether the edge estimates are confident and far from the controller's IDZ."""
        theta, errors = self.estimator.theta, self.estimator.standard_errors
        for index, reference in ((2, self.reference[0]), (5, self.reference[1])):
            if errors[index] > self.confidence:
                return False
        return any(abs(theta[i] - ref) > max(3.0 * errors[i], self.min_change)
                   for i, ref in ((2, self.reference[0]), (5, self.reference[1])))

    def _publish(self, stamp: int) -> None:
        theta, errors = self.estimator.theta, self.estimator.standard_errors
        dt = self.sample_period
        values = {
            'dead_zone_lower': theta[2], 'dead_zone_upper': theta[5],
            'saturation_negative': theta[0] / dt, 'saturation_positive': theta[3] / dt,
            'curvature_negative': theta[1], 'curvature_positive': theta[4],
            'dead_zone_lower_std': errors[2], 'dead_zone_upper_std': errors[5],
            'saturation_negative_std': errors[0] / dt, 'saturation_positive_std': errors[3] / dt,
            'curvature_negative_std': errors[1], 'curvature_positive_std': errors[4],
            'delay': self.estimator.delay * dt,
        }
        try:
            idz = idz_for_model(self.estimator.estimate(), self.control_period)
            values['slope_negative'], values['slope_positive'] = idz.slopes
        except HydroSdpError:
            idz = None
        for name, value in values.items():
            self._estimate_pubs[name].publish(Float64(data=float(value)))
        needed = self.needs_recalibration()
        self._flag_pub.publish(Bool(data=needed))
        cooled = self._last_recalibration is None or \
            stamp - self._last_recalibration >= self.cooldown * 1e9
        if needed and self.auto_recalibrate and idz is not None and cooled and \
                self._pending is None:
            self._recalibrate(idz, stamp)

    def _recalibrate(self, idz, stamp: int) -> None:
        if not self._client.service_is_ready():
            self.get_logger().warning(
                f'{self.controller_name} offers no set_parameters_atomically service; '
                'cannot recalibrate', throttle_duration_sec=5.0,
                throttle_time_source_type=self.get_clock())
            return
        request = SetParametersAtomically.Request()
        request.parameters = [_double_array('idz.dead_zone', idz.dead_zone),
                              _double_array('idz.slopes', idz.slopes)]
        self._pending = self._client.call_async(request)
        self._last_recalibration = stamp

        def done(future, edges=idz.dead_zone) -> None:
            self._pending = None
            answer = future.result()
            results = [answer.result] if answer is not None else []
            if results and all(result.successful for result in results):
                self.reference = edges
                self.recalibrations += 1
                self.get_logger().info(f'recalibrated the IDZ of {self.controller_name}: '
                                       f'edges {[round(e, 4) for e in edges]}')
            else:
                reasons = '; '.join(result.reason for result in results) or 'no answer'
                self.get_logger().warning(f'recalibration refused: {reasons}')
        self._pending.add_done_callback(done)

    def estimate(self):
        """Return the current estimate as a joint model."""
        return replace(self.estimator.estimate(), joint=self.joint)


def _double_array(name: str, values) -> ParameterMessage:
    return ParameterMessage(name=name, value=ParameterValue(
        type=ParameterType.PARAMETER_DOUBLE_ARRAY, double_array_value=[float(v) for v in values]))


def main(args: list[str] | None = None) -> None:
    """Run :class:`IdentifierNode` until shutdown (console script ``identifier_node``)."""
    run_node(IdentifierNode, args)

"""
Online identification as a ROS node (``ros2 run hydro_sdp identifier_node``).

Pairs each ``joint_states`` sample of its joint with the last valve command
received before it (the command in force over the interval that ends at the
sample, as in a recorded bag), feeds the core
:class:`~hydro_sdp.core.online.OnlineSdpIdentifier`, and publishes the estimates
and their standard deviations on ``<joint>/sdp/...`` (``std_msgs/Float64``):

* ``dead_zone_lower``, ``dead_zone_upper``: edges, input units;
* ``saturation_negative_rad_s``, ``saturation_positive_rad_s``: saturation speeds, rad/s;
* ``curvature_negative``, ``curvature_positive``: curvatures, 1/input unit;
* each of these with ``_std`` appended: its standard deviation, same unit;
* ``delay``: the delay, s;
* ``slope_negative``, ``slope_positive``: the IDZ slopes for the controller's
  ``idz.slopes`` parameter, deg per control sample per input unit;
* ``recalibration_needed`` (``std_msgs/Bool``).

The core :class:`~hydro_sdp.core.recalibration.Recalibration` decides when the
estimates call for a new IDZ; with ``auto_recalibrate`` the node then sets the
controller's ``idz.dead_zone`` and ``idz.slopes`` parameters. Every writable
parameter takes effect at once.

"""

from __future__ import annotations

from dataclasses import asdict, replace
import math
from typing import Any

from hydro_sdp.core.controller_spec import idz_for_model
from hydro_sdp.core.errors import DataError, HydroSdpError
from hydro_sdp.core.idz import InverseDeadZone
from hydro_sdp.core.model import JointModel
from hydro_sdp.core.online import input_scale, OnlineSdpIdentifier, OnlineSettings, SdpEstimate
from hydro_sdp.core.recalibration import (Decision, recalibrated_idz, Recalibration,
                                          RecalibrationPolicy)
from hydro_sdp.files import default_model_path, load_model
from hydro_sdp.ros import conversions, qos
from hydro_sdp.ros.params import declare, value_of
from hydro_sdp.ros.runner import run_node
from rcl_interfaces.msg import (Parameter as ParameterMessage, ParameterType, ParameterValue,
                                SetParametersResult)
from rcl_interfaces.srv import SetParametersAtomically
from rclpy.event_handler import PublisherEventCallbacks
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.task import Future
from sensor_msgs.msg import JointState
from std_msgs.msg import Bool, Float64

#: Recalibration thresholds, by parameter name (the fields of RecalibrationPolicy).
POLICY_PARAMETERS = ('significance', 'settle', 'confidence', 'min_change', 'cooldown')


def estimate_topics(estimate: SdpEstimate) -> dict[str, float]:
    """
    Return the estimate as topic values: saturation speeds in rad/s, the rest as they are.

    Parameters
    ----------
    estimate : SdpEstimate
        The estimate (speeds in deg/s).

    Returns
    -------
    dict[str, float]
        Value by topic name under ``<joint>/sdp/``.

    """
    values = {}
    for name, value in asdict(estimate).items():
        if name.startswith('saturation_'):
            base, std = (name[:-4], '_std') if name.endswith('_std') else (name, '')
            name, value = f'{base}_rad_s{std}', math.radians(value)
        values[name] = float(value)
    return values


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
        defaults = RecalibrationPolicy()
        declare(self, 'significance', defaults.significance,
                'edge change that counts as real, in standard deviations of the estimate',
                low=1.0, high=100.0)
        declare(self, 'settle', defaults.settle,
                'time over which an edge estimate must move less than its std, s',
                low=0.0, high=600.0)
        declare(self, 'confidence', defaults.confidence,
                'largest edge std to act on, fraction of the dead-zone width',
                low=1e-4, high=1.0)
        declare(self, 'min_change', defaults.min_change * input_scale(self.model.input_limits),
                'smallest edge change worth a recalibration, input units', low=0.0, high=1e6)
        declare(self, 'cooldown', defaults.cooldown, 'least time between recalibrations, s',
                low=0.0, high=3600.0)
        self.estimator = OnlineSdpIdentifier(
            self.model, self.sample_period,
            OnlineSettings.for_input_limits(self.model.input_limits, noise_std=noise))
        # The IDZ edges the controller uses: those of the model it was designed from.
        self.recalibration = Recalibration(self.estimator.named_estimate().edges,
                                           self._policy([]))
        self.samples = 0
        self.commands_received = 0
        self.recalibrations = 0
        #: Times of the accepted recalibrations (their requests), s of the node clock.
        self.recalibration_times: list[float] = []
        self.last_decision: Decision | None = None
        self._command: float | None = None
        self._last_publish: int | None = None
        self._pending: Future | None = None
        base = f'{self.joint}/sdp/'
        # Fifteen estimate topics: skip their QoS event handlers, which cost every wait.
        quiet = PublisherEventCallbacks(use_default_callbacks=False)
        names = tuple(estimate_topics(self.estimator.named_estimate())) + (
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
        self.add_on_set_parameters_callback(self._check_parameters)
        self.add_post_set_parameters_callback(self._apply_parameters)

    @property
    def reference(self) -> tuple[float, float]:
        """Return the IDZ edges the controller uses, input units."""
        return self.recalibration.reference

    def _policy(self, parameters: list[Parameter]) -> RecalibrationPolicy:
        # The thresholds after a set request (current values for the names it leaves out).
        return RecalibrationPolicy(**{
            name: float(value_of(parameters, name, self.get_parameter(name).value))
            for name in POLICY_PARAMETERS})

    def _check_parameters(self, parameters: list[Parameter]) -> SetParametersResult:
        try:
            self._policy(parameters)
        except HydroSdpError as error:
            return SetParametersResult(successful=False, reason=str(error))
        return SetParametersResult(successful=True)

    def _apply_parameters(self, parameters: list[Parameter]) -> None:
        # Called once the whole request is accepted: every writable parameter takes effect.
        self.recalibration.policy = self._policy([])
        self.auto_recalibrate = bool(self.get_parameter('auto_recalibrate').value)
        self.publish_period = float(self.get_parameter('publish_period').value)

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
        # The next publication is due one period after the last: a new period counts at once.
        if self._last_publish is None or \
                stamp >= self._last_publish + int(self.publish_period * 1e9):
            self._last_publish = stamp
            self._publish(stamp)

    def _publish(self, stamp: int) -> None:
        estimate = self.estimator.named_estimate()
        values = estimate_topics(estimate)
        values['delay'] = self.estimator.delay * self.sample_period
        model = self.estimator.estimate()
        decision = self.recalibration.observe(stamp * 1e-9, estimate)
        self.last_decision = decision
        try:
            values['slope_negative'], values['slope_positive'] = idz_for_model(
                model, self.control_period).slopes
        except HydroSdpError:
            pass
        for name, value in values.items():
            self._estimate_pubs[name].publish(Float64(data=float(value)))
        self._flag_pub.publish(Bool(data=decision.needed))
        if decision.due and self.auto_recalibrate and self._pending is None:
            try:
                wanted = recalibrated_idz(model, decision.edges, self.control_period)
            except HydroSdpError as error:
                self.get_logger().warning(f'no IDZ from the estimate: {error}',
                                          throttle_duration_sec=5.0,
                                          throttle_time_source_type=self.get_clock())
                return
            self._recalibrate(wanted, stamp)

    def _recalibrate(self, idz: InverseDeadZone, stamp: int) -> None:
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
        self.recalibration.attempted(stamp * 1e-9)
        edges = idz.dead_zone

        def done(future: Future) -> None:
            self._pending = None
            answer = future.result()
            results = [answer.result] if answer is not None else []
            if results and all(result.successful for result in results):
                self.recalibration.accepted(edges)
                self.recalibrations += 1
                self.recalibration_times.append(stamp * 1e-9)
                self.get_logger().info(f'recalibrated the IDZ of {self.controller_name}: '
                                       f'edges {[round(e, 4) for e in edges]}')
            else:
                reasons = '; '.join(result.reason for result in results) or 'no answer'
                self.get_logger().warning(f'recalibration refused: {reasons}')
        self._pending.add_done_callback(done)

    def estimate(self) -> JointModel:
        """Return the current estimate as a joint model."""
        return replace(self.estimator.estimate(), joint=self.joint)


def _double_array(name: str, values: tuple[float, ...]) -> ParameterMessage:
    return ParameterMessage(name=name, value=ParameterValue(
        type=ParameterType.PARAMETER_DOUBLE_ARRAY, double_array_value=[float(v) for v in values]))


def main(args: list[str] | None = None) -> None:
    """Run :class:`IdentifierNode` until shutdown (console script ``identifier_node``)."""
    run_node(IdentifierNode, args)

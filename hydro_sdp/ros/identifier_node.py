"""
Online identification as a ROS node (``ros2 run hydro_sdp identifier_node``).

One node identifies one joint (``model_file``) or several (``joints`` with
``model_files`` in the same order). Per joint it pairs each ``joint_states`` sample
with the last ``<joint>/valve_command`` received before it (the command in force
over the interval that ends at the sample, as in a recorded bag), feeds the core
:class:`~hydro_sdp.core.identification.online.OnlineSdpIdentifier`, and publishes the estimates
and their standard deviations on ``<joint>/sdp/...`` (``std_msgs/Float64``):

* ``dead_zone_lower``, ``dead_zone_upper``: edges, input units;
* ``saturation_negative_rad_s``, ``saturation_positive_rad_s``: saturation speeds, rad/s;
* ``curvature_negative``, ``curvature_positive``: curvatures, 1/input unit;
* each of these with ``_std`` appended: its standard deviation, same unit;
* ``delay``: the delay, s;
* ``slope_negative``, ``slope_positive``: the IDZ slopes for the controller's
  ``idz.slopes`` parameter, deg per control sample per input unit;
* ``recalibration_needed`` (``std_msgs/Bool``).

The core :class:`~hydro_sdp.core.control.idz_recalibration.Recalibration` decides when the
estimates call for a new IDZ; with ``auto_recalibrate`` the node then sets the
controller's ``<joint>.idz.dead_zone`` and ``<joint>.idz.slopes`` parameters
(a one-joint controller keeps its plain ``idz.*`` names in step). ``/diagnostics``
gets one status per joint every ``diagnostic_period``: the estimates with their
standard deviations, WARN when a recalibration is needed or samples stop. Every
writable parameter takes effect at once.

"""

from __future__ import annotations

from dataclasses import replace
from functools import partial
import math
from typing import Any

from diagnostic_msgs.msg import DiagnosticArray
from hydro_sdp.core.control.health import joint_health
from hydro_sdp.core.control.idz import InverseDeadZone
from hydro_sdp.core.control.idz_design import chord_idz
from hydro_sdp.core.control.idz_recalibration import recalibrated_idz, RecalibrationPolicy
from hydro_sdp.core.errors import ConfigurationError, DataError, HydroSdpError
from hydro_sdp.core.identification.online import input_scale, OnlineSdpIdentifier, OnlineSettings
from hydro_sdp.core.model.joint_model import JointModel
from hydro_sdp.io.model_files import default_model_path, load_model
from hydro_sdp.ros import conversions, qos
from hydro_sdp.ros.diagnostics import diagnostic_array
from hydro_sdp.ros.first_joint import first_joint
from hydro_sdp.ros.identifier_joint import double_array, estimate_topics, IdentifiedJoint
from hydro_sdp.ros.params import declare, value_of
from hydro_sdp.ros.runner import run_node
from rcl_interfaces.msg import SetParametersResult
from rcl_interfaces.srv import SetParametersAtomically
from rclpy.event_handler import PublisherEventCallbacks
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.task import Future
from sensor_msgs.msg import JointState
from std_msgs.msg import Bool, Float64

__all__ = ['estimate_topics', 'IdentifierNode', 'main']

#: Recalibration thresholds, by parameter name (the fields of RecalibrationPolicy).
POLICY_PARAMETERS = ('significance', 'settle', 'confidence', 'min_change', 'cooldown')


class IdentifierNode(Node):
    """
    Online SDP identifier of one or several joints, with optional automatic IDZ recalibration.

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
        joints = declare(self, 'joints', Parameter.Type.STRING_ARRAY,
                         'joints of one node, in JointState (overrides model_file)',
                         read_only=True)
        model_files = declare(self, 'model_files', Parameter.Type.STRING_ARRAY,
                              'model file of each of the joints', read_only=True)
        models = [load_model(path) for path in (model_files or [model_file])]
        if joints:
            if len(models) != len(joints) or len(set(joints)) != len(joints):
                raise ConfigurationError(f'joints needs distinct names, one per model file '
                                         f'({len(models)}), got {list(joints)}')
            names = list(joints)
        else:
            names = [declare(self, 'joint', models[0].joint, 'joint name in JointState',
                             read_only=True)]
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
        diagnostic_period = declare(self, 'diagnostic_period', 1.0,
                                    'time between /diagnostics reports, s', low=0.01,
                                    high=60.0, read_only=True)
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
        declare(self, 'min_change', defaults.min_change * input_scale(models[0].input_limits),
                'smallest edge change worth a recalibration, input units', low=0.0, high=1e6)
        declare(self, 'cooldown', defaults.cooldown, 'least time between recalibrations, s',
                low=0.0, high=3600.0)
        self.identified = [
            IdentifiedJoint(name, model, OnlineSdpIdentifier(
                model, self.sample_period,
                OnlineSettings.for_input_limits(model.input_limits, noise_std=noise)),
                self._policy([]))
            for name, model in zip(names, models)]
        self.samples = 0
        self.commands_received = 0
        # Fifteen estimate topics per joint: skip their QoS event handlers, which cost
        # every wait.
        quiet = PublisherEventCallbacks(use_default_callbacks=False)
        for item in self.identified:
            base = f'{item.joint}/sdp/'
            topics = tuple(estimate_topics(item.estimator.named_estimate())) + (
                'delay', 'slope_negative', 'slope_positive')
            item.estimate_pubs = {
                name: self.create_publisher(Float64, base + name, qos.ESTIMATE_QOS,
                                            event_callbacks=quiet)
                for name in topics}
            item.flag_pub = self.create_publisher(Bool, base + 'recalibration_needed',
                                                  qos.ESTIMATE_QOS)
            item.command_sub = self.create_subscription(
                Float64, f'{item.joint}/valve_command',
                partial(self._on_command, item=item), qos.COMMAND_QOS)
        self._state_sub = self.create_subscription(JointState, 'joint_states', self._on_state,
                                                   qos.STATE_QOS)
        self._client = self.create_client(SetParametersAtomically,
                                          f'{self.controller_name}/set_parameters_atomically')
        self._diagnostics_pub = self.create_publisher(DiagnosticArray, '/diagnostics',
                                                      qos.DIAGNOSTICS_QOS)
        self._diagnostics = self.create_timer(diagnostic_period, self.publish_diagnostics)
        self.add_on_set_parameters_callback(self._check_parameters)
        self.add_post_set_parameters_callback(self._apply_parameters)

    # The first (only) joint under the names of the one-joint node.
    joint = first_joint('identified', 'joint', "The first joint's name.")
    model = first_joint('identified', 'model', "The first joint's starting model.")
    estimator = first_joint('identified', 'estimator',
                            'The online filter of the first joint (settable).', settable=True)
    recalibration = first_joint('identified', 'recalibration',
                                "The first joint's recalibration decision.")
    last_decision = first_joint('identified', 'last_decision',
                                "The first joint's last recalibration decision.")
    recalibration_times = first_joint('identified', 'recalibration_times',
                                      "The first joint's accepted recalibration times, s.")
    reference = first_joint('identified', 'recalibration.reference',
                            'The IDZ edges the controller uses for the first joint, input units.')

    @property
    def recalibrations(self) -> int:
        """Return the recalibrations accepted, every joint together."""
        return sum(item.recalibrations for item in self.identified)

    def item(self, joint: str) -> IdentifiedJoint:
        """Return the identification of ``joint``."""
        return next(item for item in self.identified if item.joint == joint)

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
        policy = self._policy([])
        for item in self.identified:
            item.recalibration.policy = policy
        self.auto_recalibrate = bool(self.get_parameter('auto_recalibrate').value)
        self.publish_period = float(self.get_parameter('publish_period').value)

    def _on_command(self, message: Float64, item: IdentifiedJoint | None = None) -> None:
        item = item or self.identified[0]
        if math.isfinite(message.data):
            item.command = float(message.data)
            self.commands_received += 1

    def _on_state(self, message: JointState) -> None:
        read = False
        now = self.get_clock().now().nanoseconds
        for item in self.identified:
            try:
                stamp, angle = conversions.joint_angle(message, item.joint)
            except DataError as error:
                self.get_logger().warning(f'skipped a sample: {error}',
                                          throttle_duration_sec=5.0,
                                          throttle_time_source_type=self.get_clock())
                continue
            read = True
            item.angle = angle
            item.last_sample_ns = now
            if item.command is None:
                continue
            item.estimator.update(item.command, angle)
            # The next publication is due one period after the last: a new period counts at once.
            if item.last_publish is None or \
                    stamp >= item.last_publish + int(self.publish_period * 1e9):
                item.last_publish = stamp
                self._publish(item, stamp)
        if read:
            self.samples += 1

    def _publish(self, item: IdentifiedJoint, stamp: int) -> None:
        estimator = item.estimator
        estimate = estimator.named_estimate()
        values = estimate_topics(estimate)
        values['delay'] = estimator.delay * self.sample_period
        model = estimator.estimate()
        decision = item.recalibration.observe(stamp * 1e-9, estimate)
        item.last_decision = decision
        try:
            values['slope_negative'], values['slope_positive'] = chord_idz(
                model, self.control_period).slopes
        except HydroSdpError:
            pass
        for name, value in values.items():
            item.estimate_pubs[name].publish(Float64(data=float(value)))
        item.flag_pub.publish(Bool(data=decision.needed))
        if decision.due and self.auto_recalibrate and item.pending is None:
            try:
                wanted = recalibrated_idz(model, decision.edges, self.control_period)
            except HydroSdpError as error:
                self.get_logger().warning(f'{item.joint}: no IDZ from the estimate: {error}',
                                          throttle_duration_sec=5.0,
                                          throttle_time_source_type=self.get_clock())
                return
            self._recalibrate(item, wanted, stamp)

    def _recalibrate(self, item: IdentifiedJoint, idz: InverseDeadZone, stamp: int) -> None:
        if not self._client.service_is_ready():
            self.get_logger().warning(
                f'{self.controller_name} offers no set_parameters_atomically service; '
                'cannot recalibrate', throttle_duration_sec=5.0,
                throttle_time_source_type=self.get_clock())
            return
        request = SetParametersAtomically.Request()
        edges_name, slopes_name = item.parameter_names()
        request.parameters = [double_array(edges_name, idz.dead_zone),
                              double_array(slopes_name, idz.slopes)]
        item.pending = self._client.call_async(request)
        item.recalibration.attempted(stamp * 1e-9)
        edges = idz.dead_zone

        def done(future: Future) -> None:
            item.pending = None
            answer = future.result()
            results = [answer.result] if answer is not None else []
            if results and all(result.successful for result in results):
                item.recalibration.accepted(edges)
                item.recalibrations += 1
                item.recalibration_times.append(stamp * 1e-9)
                self.get_logger().info(f'recalibrated the IDZ of {item.joint} in '
                                       f'{self.controller_name}: edges '
                                       f'{[round(e, 4) for e in edges]}')
            else:
                reasons = '; '.join(result.reason for result in results) or 'no answer'
                self.get_logger().warning(f'{item.joint}: recalibration refused: {reasons}')
        item.pending.add_done_callback(done)

    def publish_diagnostics(self) -> None:
        """Publish one status per joint on ``/diagnostics``."""
        now = self.get_clock().now().nanoseconds
        stale_after = max(0.5, 10.0 * self.sample_period)
        statuses = [joint_health(item.snapshot(now, stale_after)) for item in self.identified]
        self._diagnostics_pub.publish(diagnostic_array(
            now, self.get_name(), [item.joint for item in self.identified], statuses))

    def estimate(self, joint: str | None = None) -> JointModel:
        """Return the current estimate of ``joint`` (default: the first) as a joint model."""
        item = self.identified[0] if joint is None else self.item(joint)
        return replace(item.estimator.estimate(), joint=item.joint)


def main(args: list[str] | None = None) -> None:
    """Run :class:`IdentifierNode` until shutdown (console script ``identifier_node``)."""
    run_node(IdentifierNode, args)

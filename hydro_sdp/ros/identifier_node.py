"""
Online identification as a ROS node (``ros2 run hydro_sdp identifier_node``).

Topics, parameters and lifecycle: docs/interfaces.md section 3.3.

"""

from __future__ import annotations

from dataclasses import replace
from functools import partial
import math
from typing import Unpack

from hydro_sdp.core.control.health import HealthStatus, joint_health
from hydro_sdp.core.control.idz_recalibration import recalibrated_idz, RecalibrationPolicy
from hydro_sdp.core.control.idz_table import Idz
from hydro_sdp.core.errors import ConfigurationError, DataError, HydroSdpError
from hydro_sdp.core.identification.online import input_scale, OnlineSettings
from hydro_sdp.core.identification.online_edges import online_identifier
from hydro_sdp.core.model.joint_model import JointModel
from hydro_sdp.io.model_files import default_model_path, load_model
from hydro_sdp.ros import conversions, qos
from hydro_sdp.ros.diagnostics import DiagnosticsReporter
from hydro_sdp.ros.first_joint import first_joint
from hydro_sdp.ros.identifier_joint import double_array, estimate_topics, IdentifiedJoint
from hydro_sdp.ros.node_options import NodeOptions
from hydro_sdp.ros.parameters.identifier import IDENTIFIER_PARAMETERS, POLICY_PARAMETERS
from hydro_sdp.ros.parameters.node_parameters import NodeParameters, ParameterRequest
from hydro_sdp.ros.runner import run_node
from rcl_interfaces.srv import SetParametersAtomically
from rclpy.node import Node
from rclpy.task import Future
from sensor_msgs.msg import JointState
from std_msgs.msg import Bool, Float64

__all__ = ['estimate_topics', 'IdentifierNode', 'main']


class IdentifierNode(Node):
    """
    Online SDP identifier of one or several joints, with optional automatic IDZ recalibration.

    Parameters
    ----------
    node_name : str
        ROS node name.
    **kwargs : NodeOptions
        Forwarded to :class:`rclpy.node.Node` (``context``, ``parameter_overrides``...).

    """

    #: The writable parameters in force (set by their handlers).
    publish_period: float
    auto_recalibrate: bool

    def __init__(self, *, node_name: str = 'sdp_identifier',
                 **kwargs: Unpack[NodeOptions]) -> None:
        super().__init__(node_name, **kwargs)
        self.samples = self.commands_received = 0
        self.parameters = NodeParameters(
            self, IDENTIFIER_PARAMETERS, check=self._check_request,
            apply={'publish_period': self._apply_publish_period,
                   'auto_recalibrate': self._apply_auto_recalibrate,
                   **{name: self._apply_policy for name in POLICY_PARAMETERS}})
        models = self._declare_parameters()
        self.sample_period = self.parameters.period('sample_period')
        self.control_period = self.parameters.period('control_period')
        self.controller_name = self.parameters.text('controller_node')
        self.identified = [self._identified_joint(joint, model)
                           for joint, model in zip(self._joint_names(models), models)]
        self._create_topics()
        self._client = self.create_client(SetParametersAtomically,
                                          f'{self.controller_name}/set_parameters_atomically')
        self.diagnostics = DiagnosticsReporter(self, self.parameters.double('diagnostic_period'),
                                               self._statuses)
        self.parameters.start()

    def _declare_parameters(self) -> list[JointModel]:
        """Declare the parameters; return the starting models (some defaults depend on them)."""
        parameters = self.parameters
        parameters.declare(['model_file', 'joints', 'model_files'],
                           defaults={'model_file': str(default_model_path())})
        models = [load_model(path) for path in
                  (parameters.texts('model_files') or [parameters.text('model_file')])]
        parameters.declare(defaults={'min_change': RecalibrationPolicy().min_change *
                                     input_scale(models[0].input_limits)})
        return models

    def _joint_names(self, models: list[JointModel]) -> list[str]:
        """Return the joints' names: ``joints``, or the ``joint`` of a one-joint node."""
        joints = self.parameters.texts('joints')
        if not joints:
            self.parameters.declare(['joint'], defaults={'joint': models[0].joint})
            return [self.parameters.text('joint')]
        if len(models) != len(joints) or len(set(joints)) != len(joints):
            raise ConfigurationError(f'joints needs distinct names, one per model file '
                                     f'({len(models)}), got {joints}')
        return joints

    def _identified_joint(self, joint: str, model: JointModel) -> IdentifiedJoint:
        """Return a joint's online filter and recalibration decision, from its start model."""
        settings = OnlineSettings.for_input_limits(
            model.input_limits, noise_std=self.parameters.double('noise_std'))
        return IdentifiedJoint(joint, model,
                               online_identifier(model, self.sample_period, settings),
                               self._policy(ParameterRequest([])))

    def _create_topics(self) -> None:
        """Create each joint's estimate topics and command subscription, and joint_states'."""
        quiet = qos.QUIET_PUBLISHER       # fifteen estimate topics per joint
        events = qos.subscription_events(self.context)
        for item in self.identified:
            base = f'{item.joint}/sdp/'
            topics = tuple(estimate_topics(item.estimator.named_estimate())) + (
                'delay', 'slope_negative', 'slope_positive')
            item.estimate_pubs = {
                name: self.create_publisher(Float64, base + name, qos.ESTIMATE_QOS,
                                            event_callbacks=quiet)
                for name in topics}
            item.flag_pub = self.create_publisher(Bool, base + 'recalibration_needed',
                                                  qos.ESTIMATE_QOS, event_callbacks=quiet)
            self.create_subscription(Float64, f'{item.joint}/valve_command',
                                     partial(self._on_command, item=item), qos.COMMAND_QOS,
                                     event_callbacks=events)
        self.create_subscription(JointState, 'joint_states', self._on_state, qos.STATE_QOS,
                                 event_callbacks=events)

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

    def _policy(self, request: ParameterRequest) -> RecalibrationPolicy:
        # The thresholds after a set request (current values for the names it leaves out).
        return RecalibrationPolicy(**{
            name: request.number(name, self.parameters.double(name))
            for name in POLICY_PARAMETERS})

    def _check_request(self, request: ParameterRequest) -> None:
        self._policy(request)

    def _apply_policy(self) -> None:
        policy = self._policy(ParameterRequest([]))
        for item in self.identified:
            item.recalibration.policy = policy

    def _apply_publish_period(self) -> None:
        self.publish_period = self.parameters.double('publish_period')

    def _apply_auto_recalibrate(self) -> None:
        self.auto_recalibrate = self.parameters.flag('auto_recalibrate')

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
            values['slope_negative'], values['slope_positive'] = recalibrated_idz(
                model, estimate.edges, self.control_period, item.form).slopes
        except HydroSdpError:
            pass
        for name, value in values.items():
            item.estimate_pubs[name].publish(Float64(data=float(value)))
        assert item.flag_pub is not None
        item.flag_pub.publish(Bool(data=decision.needed))
        if decision.due and self.auto_recalibrate and item.pending is None:
            try:
                wanted = recalibrated_idz(model, decision.edges, self.control_period, item.form)
            except HydroSdpError as error:
                self.get_logger().warning(f'{item.joint}: no IDZ from the estimate: {error}',
                                          throttle_duration_sec=5.0,
                                          throttle_time_source_type=self.get_clock())
                return
            self._recalibrate(item, wanted, stamp)

    def _recalibrate(self, item: IdentifiedJoint, idz: Idz, stamp: int) -> None:
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

    def _statuses(self, now_ns: int) -> list[tuple[str, HealthStatus]]:
        stale_after = max(0.5, 10.0 * self.sample_period)
        return [(item.joint, joint_health(item.snapshot(now_ns, stale_after)))
                for item in self.identified]

    def publish_diagnostics(self) -> None:
        """Publish one status per joint on ``/diagnostics`` now."""
        self.diagnostics.publish()

    def estimate(self, joint: str | None = None) -> JointModel:
        """Return the current estimate of ``joint`` (default: the first) as a joint model."""
        item = self.identified[0] if joint is None else self.item(joint)
        return replace(item.estimator.estimate(), joint=item.joint)


def main(args: list[str] | None = None) -> None:
    """Run :class:`IdentifierNode` until shutdown (console script ``identifier_node``)."""
    run_node(IdentifierNode, args)

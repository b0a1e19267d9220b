"""
The PIP-IDZ controller as a ROS node (``ros2 run hydro_sdp controller_node``).

The core :class:`~hydro_sdp.core.pip_controller.PipIdzController` does the
control and the core :mod:`~hydro_sdp.core.scheduling` decides when: the first
JointState sample at or after each control instant is controlled (so the
feedback-to-command latency is the computation time); a duplicate or
out-of-order sample is ignored; a sample that cannot be used (NaN, joint
missing, arrays of different lengths, stamp further than ``feedback_timeout``
from the node's clock) is refused with a throttled warning and the valve is
closed; if no valid feedback arrives for ``feedback_timeout`` the watchdog
closes the valve, and control resumes from the next valid sample without a bump.
Set-points are kept ``setpoint_margin`` degrees inside the end stops
(:mod:`~hydro_sdp.core.safety`). This node only wires these to ROS: topics, unit
conversions, logging and parameters.

Every writable parameter applies at run time. A change request is checked as a
whole before anything is applied (an atomic request with a valid IDZ and unstable
gains changes nothing) and applied in the post-set callback.

"""

from __future__ import annotations

from dataclasses import replace
import math
from typing import Any

from hydro_sdp.core.controller_spec import ControllerSpec, design_from_model
from hydro_sdp.core.errors import DataError, HydroSdpError
from hydro_sdp.core.idz import idz_mode, IDZ_MODES, InverseDeadZone
from hydro_sdp.core.pip_controller import PipIdzController
from hydro_sdp.core.pip_design import PipGains
from hydro_sdp.core.safety import check_controller_fits, clamp_setpoint, SETPOINT_MARGIN, \
    setpoint_range
from hydro_sdp.core.scheduling import ControlSchedule, FeedbackGate, seconds_to_ns, \
    watchdog_period_ns
from hydro_sdp.files import default_model_path, load_controller, load_model
from hydro_sdp.ros import qos
from hydro_sdp.ros.conversions import joint_angle
from hydro_sdp.ros.params import declare, pair, value_of
from hydro_sdp.ros.runner import run_node
from rcl_interfaces.msg import SetParametersResult
from rclpy.node import Node
from rclpy.parameter import Parameter
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64

IDZ_PARAMETERS = ('idz.dead_zone', 'idz.slopes', 'idz.beta', 'idz.mode')
GAIN_PARAMETERS = ('gains.f', 'gains.g', 'gains.k_i')


class PipControllerNode(Node):
    """
    PIP-IDZ control of one joint from ``joint_states`` and ``<joint>/setpoint``.

    Parameters
    ----------
    node_name : str
        ROS node name.
    **kwargs : Any
        Forwarded to :class:`rclpy.node.Node` (``context``, ``parameter_overrides``...).

    """

    def __init__(self, *, node_name: str = 'pip_controller', **kwargs: Any) -> None:
        super().__init__(node_name, **kwargs)
        model_file = declare(self, 'model_file', str(default_model_path()),
                             'model file of the joint', read_only=True)
        controller_file = declare(self, 'controller_file', '',
                                  'controller file from hydro-sdp design (default: designed '
                                  'from the model at start-up)', read_only=True)
        period = declare(self, 'control_period', 0.05,
                         'control period when designing from the model, s',
                         low=1e-3, high=10.0, read_only=True)
        self.model = load_model(model_file)
        if controller_file:
            spec = load_controller(controller_file)
            check_controller_fits(spec, self.model)
        else:
            spec = design_from_model(self.model, control_period=period)
        self.joint = declare(self, 'joint', spec.joint, 'joint name in JointState',
                             read_only=True)
        self.feedback_timeout = declare(self, 'feedback_timeout', 0.5,
                                        'watchdog: close the valve after this long without '
                                        'valid feedback, s', low=1e-3, high=60.0)
        self.setpoint_margin = declare(self, 'setpoint_margin', SETPOINT_MARGIN,
                                       'set-points are kept this far inside the end stops, deg',
                                       low=0.0, high=90.0)
        setpoint_range(self.model.angle_limits, self.setpoint_margin)   # leaves room?
        gains = spec.gains
        declare(self, 'gains.f', list(gains.f),
                'PIP output feedback gains f0.., (deg per control sample) per deg')
        declare(self, 'gains.g', list(gains.g) or Parameter.Type.DOUBLE_ARRAY,
                'PIP input feedback gains g1.. (dimensionless)')
        declare(self, 'gains.k_i', gains.k_i,
                'PIP integral gain kI, (deg per control sample) per deg of error',
                low=0.0, high=10.0)
        idz = spec.idz
        if idz is not None:
            declare(self, 'idz.dead_zone', list(idz.dead_zone), 'IDZ edges, input units')
            declare(self, 'idz.slopes', list(idz.slopes),
                    'IDZ slopes, deg per control sample per input unit')
            declare(self, 'idz.beta', idz.beta, 'IDZ chatter band, deg per control sample',
                    low=0.0, high=100.0)
            declare(self, 'idz.mode', idz.mode, f"IDZ mode: {', '.join(IDZ_MODES)}")
        self.spec = spec
        self.controller = PipIdzController(spec.settings())
        self._rest = idz.rest if idz is not None else 0.0
        self.schedule = ControlSchedule(seconds_to_ns(spec.control_period))
        timeout_ns = seconds_to_ns(self.feedback_timeout)
        self._clock_handle = self.get_clock().handle
        self.gate = FeedbackGate(timeout_ns, self._now_ns())
        self._setpoint: float | None = None
        self.samples = 0
        self.outputs = 0
        self.refused = 0
        self.setpoints_received = 0
        self.last_command = self._rest
        self._command_pub = self.create_publisher(Float64, f'{self.joint}/valve_command',
                                                  qos.COMMAND_QOS)
        self._state_sub = self.create_subscription(JointState, 'joint_states',
                                                   self._on_state, qos.STATE_QOS)
        self._setpoint_sub = self.create_subscription(Float64, f'{self.joint}/setpoint',
                                                      self._on_setpoint, qos.COMMAND_QOS)
        self.add_on_set_parameters_callback(self._check_parameters)
        self.add_post_set_parameters_callback(self._apply_parameters)
        self._watchdog = self.create_timer(watchdog_period_ns(timeout_ns) * 1e-9,
                                           self._on_watchdog)

    @property
    def _blind(self) -> bool:
        """Whether the watchdog found no valid feedback (the valve is closed)."""
        return self.gate.blind

    def _warn(self, text: str) -> None:
        self.get_logger().warning(text, throttle_duration_sec=1.0,
                                  throttle_time_source_type=self.get_clock())

    def _publish(self, command: float) -> None:
        self.last_command = command
        self._command_pub.publish(Float64(data=float(command)))

    def _close_valve(self) -> None:
        self._publish(self._rest)
        self.schedule.hold()

    def _on_setpoint(self, message: Float64) -> None:
        self.setpoints_received += 1
        value = float(message.data)
        if not math.isfinite(value):
            self._warn(f'refused a non-finite set-point; keeping {self._setpoint}')
            return
        self._setpoint = self._safe_setpoint(math.degrees(value))

    def _safe_setpoint(self, setpoint: float) -> float:
        safe = clamp_setpoint(setpoint, self.model.angle_limits, self.setpoint_margin)
        if safe != setpoint:
            self._warn(f'set-point {setpoint:.2f} deg is beyond the end stops '
                       f'{list(self.model.angle_limits or ())} less the margin '
                       f'{self.setpoint_margin:g} deg; using {safe:.2f} deg')
        return safe

    def _now_ns(self) -> int:
        # The node clock's reading without building an rclpy Time: it is read for every sample.
        handle = self._clock_handle
        with handle:
            return handle.get_now().nanoseconds

    def _on_state(self, message: JointState) -> None:
        # Every sample comes through here: the rare paths (refusals, warnings) go to methods.
        self.samples += 1
        try:
            stamp, angle = joint_angle(message, self.joint)
            admission = self.gate.admit(stamp, self._now_ns())
        except DataError as error:
            self._refuse(error)
            return
        if admission != 'accepted':
            if admission == 'ignored':
                self._ignore(stamp)
                return
            self.get_logger().info('feedback is back; control resumes')
        schedule = self.schedule
        tick = schedule.tick(stamp)
        if tick == 'wait':
            return
        controller = self.controller
        if tick == 'resume':
            # Resume bumplessly: the valve was closed, so the last applied increment is 0.
            controller.reset(u=0.0)
        setpoint = self._setpoint
        if setpoint is None:
            setpoint = self._setpoint = angle   # hold where the joint is until told otherwise
        try:
            _, command = controller.step(setpoint, angle)
        except HydroSdpError as error:
            self._warn(f'controller refused the sample ({error}); valve closed')
            self._close_valve()
            return
        self.last_command = command
        self._command_pub.publish(Float64(data=float(command)))
        self.outputs += 1
        schedule.stepped(stamp)

    def _refuse(self, error: DataError) -> None:
        self.refused += 1
        self._warn(f'refused feedback ({error}); valve closed')
        self._close_valve()

    def _ignore(self, stamp: int) -> None:
        # A duplicate or a sample overtaken by a newer one: the command in force was
        # computed from fresher feedback, so it stays; the sample is only dropped.
        self.refused += 1
        self._warn(f'ignored JointState stamp {stamp * 1e-9:.6f} s: it is not after '
                   f'the last one ({(self.gate.last_stamp or 0) * 1e-9:.6f} s)')

    def _on_watchdog(self) -> None:
        now = self._now_ns()
        state = self.gate.watchdog(now)
        if state == 'lost':
            self._warn(f'no valid feedback for {self.gate.silence_ns(now) * 1e-9:.2f} s; '
                       'valve closed')
        if state != 'fed':
            self._close_valve()

    def _candidate(self, parameters: list[Parameter]) -> ControllerSpec:
        """Return the spec a set request would give; raises if it is not valid."""
        names = {parameter.name for parameter in parameters}
        spec = self.spec
        if names & set(IDZ_PARAMETERS) and spec.idz is not None:
            current = spec.idz
            idz = InverseDeadZone(
                dead_zone=pair(value_of(parameters, 'idz.dead_zone', current.dead_zone),
                               'idz.dead_zone'),
                slopes=pair(value_of(parameters, 'idz.slopes', current.slopes), 'idz.slopes'),
                beta=float(value_of(parameters, 'idz.beta', current.beta)),
                mode=idz_mode(value_of(parameters, 'idz.mode', current.mode)),
                rest=current.rest)
            spec = replace(spec, idz=idz)    # checks the IDZ against the valve range
        if names & set(GAIN_PARAMETERS):
            current_gains = spec.gains
            gains = PipGains(
                f=tuple(float(x) for x in value_of(parameters, 'gains.f', current_gains.f)),
                g=tuple(float(x) for x in value_of(parameters, 'gains.g', current_gains.g) or ()),
                k_i=float(value_of(parameters, 'gains.k_i', current_gains.k_i)))
            spec = replace(spec, gains=gains)   # checks orders and closed-loop stability
        return spec

    def _check_parameters(self, parameters: list[Parameter]) -> SetParametersResult:
        # On-set: validate the whole request; nothing is applied here.
        try:
            self._candidate(parameters)
            margin = value_of(parameters, 'setpoint_margin', self.setpoint_margin)
            setpoint_range(self.model.angle_limits, float(margin))
        except (HydroSdpError, TypeError, ValueError) as error:
            return SetParametersResult(successful=False, reason=str(error))
        return SetParametersResult(successful=True)

    def _apply_parameters(self, parameters: list[Parameter]) -> None:
        # Post-set: the request was accepted as a whole; apply all of it.
        names = {parameter.name for parameter in parameters}
        spec = self._candidate(parameters)
        if spec.idz is not None and spec.idz != self.spec.idz:
            self.controller.update_idz(spec.idz)
            self.get_logger().info(f'IDZ now edges {list(spec.idz.dead_zone)}, slopes '
                                   f'{[round(s, 4) for s in spec.idz.slopes]}')
        if spec.gains != self.spec.gains:
            self.controller.update_gains(spec.gains)
            self.get_logger().info(f'gains now f {list(spec.gains.f)}, g {list(spec.gains.g)}, '
                                   f'kI {spec.gains.k_i}')
        self.spec = spec
        if 'feedback_timeout' in names:
            self.feedback_timeout = float(value_of(parameters, 'feedback_timeout', 0.0))
            timeout_ns = seconds_to_ns(self.feedback_timeout)
            self.gate.timeout_ns = timeout_ns
            self._watchdog.timer_period_ns = watchdog_period_ns(timeout_ns)
            self.get_logger().info(f'feedback_timeout now {self.feedback_timeout:g} s')
        if 'setpoint_margin' in names:
            self.setpoint_margin = float(value_of(parameters, 'setpoint_margin', 0.0))
            if self._setpoint is not None:
                self._setpoint = self._safe_setpoint(self._setpoint)


def main(args: list[str] | None = None) -> None:
    """Run :class:`PipControllerNode` until shutdown (console script ``controller_node``)."""
    run_node(PipControllerNode, args)

"""
The PIP-IDZ controller as a ROS node (``ros2 run hydro_sdp controller_node``).

The core :class:`~hydro_sdp.core.pip_controller.PipIdzController` does the
control; this node only decides when (the first JointState sample at or after
each control instant, so the feedback-to-command latency is the computation
time), converts units, keeps the valve safe and exposes the gains and the IDZ
as parameters. Safety: set-points beyond the end stops are clamped; a sample
that cannot be used (NaN, joint missing, arrays of different lengths, stamp
further than ``feedback_timeout`` from the node's clock) is refused with a
throttled warning and the valve is closed; a duplicate or out-of-order sample
is ignored (the command in force came from fresher feedback); if no valid
feedback arrives for ``feedback_timeout`` the watchdog closes the valve, and
control resumes from the next valid sample without a bump.

"""

from __future__ import annotations

from dataclasses import replace
import math
from typing import Any

from hydro_sdp.core.controller_spec import ControllerSpec, design_from_model
from hydro_sdp.core.errors import DataError, HydroSdpError
from hydro_sdp.core.idz import IDZ_MODES, InverseDeadZone
from hydro_sdp.core.pip_controller import PipIdzController
from hydro_sdp.core.pip_design import PipGains
from hydro_sdp.files import default_model_path, load_controller, load_model
from hydro_sdp.ros import conversions, qos
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
        spec = load_controller(controller_file) if controller_file else \
            design_from_model(self.model, control_period=period)
        self.joint = declare(self, 'joint', spec.joint, 'joint name in JointState',
                             read_only=True)
        self.feedback_timeout = declare(self, 'feedback_timeout', 0.5,
                                        'watchdog: close the valve after this long without '
                                        'valid feedback, s', low=1e-3, high=60.0)
        gains = spec.gains
        declare(self, 'gains.f', list(gains.f), 'PIP output feedback gains f0..')
        declare(self, 'gains.g', list(gains.g) or Parameter.Type.DOUBLE_ARRAY,
                'PIP input feedback gains g1..')
        declare(self, 'gains.k_i', gains.k_i, 'PIP integral gain kI', low=0.0, high=10.0)
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
        self._period_ns = int(round(spec.control_period * 1e9))
        self._next_instant: int | None = None
        self._last_stamp: int | None = None
        self._setpoint: float | None = None
        self._blind = False
        self._restart = True
        self._last_valid = self.get_clock().now().nanoseconds
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
        self._watchdog = self.create_timer(min(self.feedback_timeout / 2.0, 0.1),
                                           self._on_watchdog)

    def _warn(self, text: str) -> None:
        self.get_logger().warning(text, throttle_duration_sec=1.0,
                                  throttle_time_source_type=self.get_clock())

    def _publish(self, command: float) -> None:
        self.last_command = command
        self._command_pub.publish(Float64(data=float(command)))

    def _close_valve(self) -> None:
        self._publish(self._rest)
        self._restart = True

    def _on_setpoint(self, message: Float64) -> None:
        self.setpoints_received += 1
        value = float(message.data)
        if not math.isfinite(value):
            self._warn(f'refused a non-finite set-point; keeping {self._setpoint}')
            return
        setpoint = math.degrees(value)
        limits = self.model.angle_limits
        if limits is not None and not limits[0] <= setpoint <= limits[1]:
            clamped = min(max(setpoint, limits[0]), limits[1])
            self._warn(f'set-point {setpoint:.2f} deg is beyond the end stops {list(limits)}; '
                       f'using {clamped:.2f} deg')
            setpoint = clamped
        self._setpoint = setpoint

    def _on_state(self, message: JointState) -> None:
        self.samples += 1
        try:
            stamp, angle = conversions.joint_angle(message, self.joint)
            if self._last_stamp is not None and stamp <= self._last_stamp:
                # A duplicate or a sample overtaken by a newer one: the command in force was
                # computed from fresher feedback, so it stays; the sample is only dropped.
                self.refused += 1
                self._warn(f'ignored JointState stamp {stamp * 1e-9:.6f} s: it is not after '
                           f'the last one ({self._last_stamp * 1e-9:.6f} s)')
                return
            self._check_freshness(stamp)
        except DataError as error:
            self.refused += 1
            self._warn(f'refused feedback ({error}); valve closed')
            self._close_valve()
            return
        self._last_stamp = stamp
        self._last_valid = self.get_clock().now().nanoseconds
        if self._blind:
            self.get_logger().info('feedback is back; control resumes')
            self._blind = False
        if self._next_instant is None or self._restart:
            self._next_instant = stamp if self._next_instant is None else self._next_instant
            if self._restart:
                # Resume bumplessly: the valve was closed, so the last applied increment is 0.
                self.controller.reset(u=0.0)
                self._restart = False
        if stamp < self._next_instant:
            return
        setpoint = self._setpoint if self._setpoint is not None else angle
        if self._setpoint is None:
            self._setpoint = angle        # hold where the joint is until told otherwise
        try:
            _, command = self.controller.step(setpoint, angle)
        except HydroSdpError as error:
            self._warn(f'controller refused the sample ({error}); valve closed')
            self._close_valve()
            return
        self._publish(command)
        self.outputs += 1
        missed = (stamp - self._next_instant) // self._period_ns
        self._next_instant += (missed + 1) * self._period_ns

    def _check_freshness(self, stamp: int) -> None:
        # A stamp far from this node's clock is stale feedback or a clock mix-up; one from the
        # future would also make every later sample look old, so neither is accepted.
        now = self.get_clock().now().nanoseconds
        if now == 0:
            return          # simulated time that has not started yet
        lead = (stamp - now) * 1e-9
        if abs(lead) > self.feedback_timeout:
            where = 'ahead of' if lead > 0 else 'behind'
            raise DataError(f'JointState stamp is {abs(lead):.3f} s {where} the node clock '
                            f'(more than feedback_timeout {self.feedback_timeout} s; '
                            'check use_sim_time on every node)')

    def _on_watchdog(self) -> None:
        silent = self.get_clock().now().nanoseconds - self._last_valid
        if silent > self.feedback_timeout * 1e9:
            if not self._blind:
                self._warn(f'no valid feedback for {silent * 1e-9:.2f} s; valve closed')
            self._blind = True
            self._close_valve()

    def _check_parameters(self, parameters: list[Parameter]) -> SetParametersResult:
        names = {parameter.name for parameter in parameters}
        try:
            if names & set(IDZ_PARAMETERS):
                current = self.controller.settings.idz
                idz = InverseDeadZone(
                    dead_zone=pair(value_of(parameters, 'idz.dead_zone', current.dead_zone),
                                   'idz.dead_zone'),
                    slopes=pair(value_of(parameters, 'idz.slopes', current.slopes),
                                'idz.slopes'),
                    beta=float(value_of(parameters, 'idz.beta', current.beta)),
                    mode=str(value_of(parameters, 'idz.mode', current.mode)),
                    rest=current.rest)
                replace(self.controller.settings, idz=idz)   # validates against the valve
                self.controller.update_idz(idz)
                self.get_logger().info(f'IDZ now edges {list(idz.dead_zone)}, slopes '
                                       f'{[round(s, 4) for s in idz.slopes]}')
            if names & set(GAIN_PARAMETERS):
                current = self.controller.settings.gains
                gains = PipGains(
                    f=tuple(value_of(parameters, 'gains.f', current.f)),
                    g=tuple(value_of(parameters, 'gains.g', current.g) or ()),
                    k_i=float(value_of(parameters, 'gains.k_i', current.k_i)))
                candidate = ControllerSpec(self.spec.joint, self.spec.control_period,
                                           self.spec.plant, gains, self.spec.idz,
                                           self.spec.u_limits, self.spec.v_limits)
                self.controller.update_gains(candidate.gains)
        except (HydroSdpError, TypeError, ValueError) as error:
            return SetParametersResult(successful=False, reason=str(error))
        return SetParametersResult(successful=True)


def main(args: list[str] | None = None) -> None:
    """Run :class:`PipControllerNode` until shutdown (console script ``controller_node``)."""
    run_node(PipControllerNode, args)

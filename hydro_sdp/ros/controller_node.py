"""
The PIP-IDZ controller as a ROS lifecycle node (``ros2 run hydro_sdp controller_node``).

Topics, parameters and lifecycle: docs/interfaces.md section 3.2.

"""

from __future__ import annotations

import math
import time
from typing import Callable, Sequence, Unpack

from hydro_sdp.core.control.health import HealthStatus, joint_health
from hydro_sdp.core.control.safety import clamp_setpoint, setpoint_range
from hydro_sdp.core.control.scheduling import seconds_to_ns
from hydro_sdp.core.errors import ConfigurationError, DataError, HydroSdpError
from hydro_sdp.io.model_files import default_model_path
from hydro_sdp.ros.controller_configuration import ControllerConfiguration
from hydro_sdp.ros.controller_interfaces import ControllerInterfaces
from hydro_sdp.ros.conversions import fill_controller_state, position_of
from hydro_sdp.ros.diagnostics import DiagnosticsReporter
from hydro_sdp.ros.first_joint import first_joint
from hydro_sdp.ros.joint_loop import JointLoop
from hydro_sdp.ros.node_options import NodeOptions
from hydro_sdp.ros.parameters.controller import CONTROLLER_PARAMETERS
from hydro_sdp.ros.parameters.node_parameters import NodeParameters, ParameterRequest
from hydro_sdp.ros.runner import run_node
from hydro_sdp.ros.trajectory_follower import TrajectoryFollower
from rclpy.lifecycle import LifecycleNode, LifecycleState, TransitionCallbackReturn
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64
from trajectory_msgs.msg import JointTrajectory as TrajectoryMessage

SUCCESS = TransitionCallbackReturn.SUCCESS


class PipControllerNode(LifecycleNode):
    """
    PIP-IDZ control of one or several joints from ``joint_states``, set-points and trajectories.

    Parameters
    ----------
    node_name : str
        ROS node name.
    **kwargs : NodeOptions
        Forwarded to :class:`rclpy.lifecycle.LifecycleNode` (``context``...).

    """

    #: The writable parameters in force (set by their handlers, read per message).
    feedback_timeout: float
    setpoint_margin: float
    stop_band: float
    feedback_margin: float
    feedforward: bool

    def __init__(self, *, node_name: str = 'pip_controller',
                 **kwargs: Unpack[NodeOptions]) -> None:
        LifecycleNode.__init__(self, node_name, **kwargs)
        self.loops: list[JointLoop] = []
        self.active = False
        self.interfaces: ControllerInterfaces | None = None
        self.diagnostics: DiagnosticsReporter | None = None
        self.samples = self.outputs = self.refused = 0
        self.setpoints_received = self.trajectories_received = self.trajectories_refused = 0
        self.trajectories: TrajectoryFollower | None = None
        self._configure_error: HydroSdpError | None = None
        self._clock_handle = self.get_clock().handle
        #: The steady clock the watchdog also counts on, ns (a simulated clock that stops must
        #: not stop it); an in-process harness that is the only clock sets its own.
        self.steady_clock: Callable[[], int] = time.monotonic_ns
        self.parameters = NodeParameters(
            self, CONTROLLER_PARAMETERS, check=self._check_request,
            apply={'feedback_timeout': self._apply_feedback_timeout,
                   'setpoint_margin': self._apply_setpoint_margin,
                   'stop_band': self._apply_stop_band,
                   'feedback_margin': self._apply_feedback_margin,
                   'feedforward': self._apply_feedforward},
            apply_joint=self._apply_joints)
        self.parameters.declare(defaults={'model_file': str(default_model_path())})
        self.parameters.start()
        self.configuration = ControllerConfiguration(self.parameters)
        if self.parameters.flag('autostart'):
            if self.trigger_configure() != SUCCESS:
                raise self._configure_error or ConfigurationError('configuration failed')
            self.trigger_activate()

    # Single-joint names of earlier versions: the first (only) joint's state.
    joint = first_joint('loops', 'joint', "The first joint's name.")
    controller = first_joint('loops', 'controller',
                             "The first joint's :class:`PipIdzController`.")
    spec = first_joint('loops', 'spec', "The first joint's controller spec.")
    model = first_joint('loops', 'model', "The first joint's model.")
    gate = first_joint('loops', 'gate', "The first joint's feedback gate.")
    last_command = first_joint('loops', 'last_command', "The first joint's last valve command.")

    @property
    def joints(self) -> list[str]:
        """Return the controlled joints."""
        return [loop.joint for loop in self.loops]

    def loop(self, joint: str) -> JointLoop:
        """Return the loop of ``joint``."""
        return next(loop for loop in self.loops if loop.joint == joint)

    # Lifecycle.
    def on_configure(self, state: LifecycleState) -> TransitionCallbackReturn:
        """Load the files, design, declare the joints' parameters, create the interfaces."""
        try:
            loops = self.configuration.build(
                seconds_to_ns(self.feedback_timeout), self.setpoint_margin, self._now_ns(),
                feedback_margin=self.feedback_margin, stop_band=self.stop_band)
        except (HydroSdpError, OSError) as error:
            self._configure_error = error if isinstance(error, HydroSdpError) \
                else ConfigurationError(str(error))
            self.get_logger().error(f'configuration failed: {error}')
            return TransitionCallbackReturn.FAILURE
        self.loops = loops
        self.trajectories = TrajectoryFollower(loops)
        self.interfaces = ControllerInterfaces(
            self, loops, on_state=self._on_state, on_setpoint=self._on_setpoint,
            on_trajectory=self._on_trajectory, on_watchdog=self._on_watchdog,
            timeout_ns=seconds_to_ns(self.feedback_timeout))
        self.diagnostics = DiagnosticsReporter(
            self, self.parameters.double('diagnostic_period'), self._statuses)
        return SUCCESS

    def on_activate(self, state: LifecycleState) -> TransitionCallbackReturn:
        """Start commanding; every joint holds where the next sample finds it."""
        now = self._now_ns()
        for loop in self.loops:
            loop.reset(now)
        self.trajectories = TrajectoryFollower(self.loops)
        self.active = True
        return SUCCESS

    def on_deactivate(self, state: LifecycleState) -> TransitionCallbackReturn:
        """Close every valve once and stop commanding."""
        self.active = False
        for loop in self.loops:
            loop.close_valve()
        return SUCCESS

    def on_cleanup(self, state: LifecycleState) -> TransitionCallbackReturn:
        """Undo configure."""
        if self.interfaces is not None:
            self.interfaces.destroy(self.loops)
            self.interfaces = None
        if self.diagnostics is not None:
            self.diagnostics.destroy()
            self.diagnostics = None
        self.configuration.release(self.loops)
        self.loops = []
        return SUCCESS

    def on_shutdown(self, state: LifecycleState) -> TransitionCallbackReturn:
        """Close the valves if commanding, and release everything."""
        if self.active:
            self.on_deactivate(state)
        return self.on_cleanup(state)

    def state_label(self) -> str:
        """Return the lifecycle state's label (``active``, ``inactive``...)."""
        return str(self._state_machine.current_state[1])

    # Control: every sample comes through _on_state; rare paths (refusals, warnings) are
    # methods of their own, so the common path stays short.
    def _on_state(self, message: JointState) -> None:
        self.samples += 1
        if not self.active:
            return
        stamp = message.header.stamp
        stamp_ns = stamp.sec * 1_000_000_000 + stamp.nanosec
        names = message.name
        positions = message.position
        now = self._now_ns()
        steady = self.steady_clock()
        for loop in self.loops:
            self._control(loop, stamp_ns, names, positions, now, steady)

    def _control(self, loop: JointLoop, stamp: int, names: Sequence[str],
                 positions: Sequence[float], now: int, steady: int) -> None:
        try:
            angle = position_of(names, positions, loop.joint)
            admission = loop.gate.admit(stamp, now, steady)
            if admission != 'ignored':
                loop.plausibility.check(stamp, angle)
        except DataError as error:
            self._refuse(loop, error)
            return
        if admission != 'accepted':
            if admission == 'ignored':
                self._ignore(loop, stamp)
                return
            self.get_logger().info(f'{loop.joint}: feedback is back; control resumes')
        loop.angle = angle
        schedule = loop.schedule
        tick = schedule.tick(stamp)
        if tick == 'wait':
            return
        controller = loop.controller
        if tick == 'resume':
            # Resume bumplessly: the valve was closed, so the last applied increment is 0.
            controller.reset(u=0.0)
        feedforward: float | None = None
        if loop.following:
            assert self.trajectories is not None
            setpoint, feedforward = self.trajectories.setpoint(loop, stamp * 1e-9,
                                                               self.feedforward)
        elif loop.setpoint is not None:
            setpoint = loop.setpoint
        else:
            setpoint = loop.setpoint = angle   # hold where the joint is until told otherwise
        # Where the joint is headed: the increments already sent still move it a delay on.
        headed = angle + controller.pending(loop.spec.delay_samples)
        if loop.stop_hold.decide(setpoint, headed, loop.allowed):
            self._hold_at_stop(loop, setpoint, angle, stamp)
            return
        try:
            u, command = controller.step(setpoint, angle, feedforward)
        except HydroSdpError as error:
            self._warn(f'{loop.joint}: controller refused the sample ({error}); valve closed')
            loop.close_valve()
            return
        loop.publish_command(command)
        # After the command, so none of it adds to the feedback-to-command latency.
        loop.last_setpoint = setpoint
        self.outputs += 1
        schedule.stepped(stamp)
        self._report_step(loop, setpoint, angle, u, command)

    def _hold_at_stop(self, loop: JointLoop, setpoint: float, angle: float,
                      stamp: int) -> None:
        # Near a set-point at a stop the valve rests in its dead-zone: driving on would
        # press the cylinder into the stop. The next step starts from rest.
        loop.close_valve()
        loop.last_setpoint = setpoint
        self.outputs += 1
        loop.schedule.stepped(stamp)
        loop.schedule.hold()
        self._report_step(loop, setpoint, angle, 0.0, loop.rest)

    def _report_step(self, loop: JointLoop, setpoint: float, angle: float, u: float,
                     command: float) -> None:
        # Skipped, serialisation and all, while nobody listens.
        state_pub = loop.state_pub
        interfaces = self.interfaces
        if state_pub is not None and interfaces is not None and \
                state_pub.get_subscription_count():
            state_pub.publish(fill_controller_state(interfaces.state_message, setpoint, angle,
                                                    u, command))

    def _refuse(self, loop: JointLoop, error: DataError) -> None:
        self.refused += 1
        loop.refused_since_report += 1
        self._warn(f'{loop.joint}: refused feedback ({error}); valve closed')
        loop.close_valve()

    def _ignore(self, loop: JointLoop, stamp: int) -> None:
        # A duplicate or a sample overtaken by a newer one: the command in force was
        # computed from fresher feedback, so it stays; the sample is only dropped.
        self.refused += 1
        self._warn(f'{loop.joint}: ignored JointState stamp {stamp * 1e-9:.6f} s: it is not '
                   f'after the last one ({(loop.gate.last_stamp or 0) * 1e-9:.6f} s)')

    def _warn(self, text: str) -> None:
        self.get_logger().warning(text, throttle_duration_sec=1.0,
                                  throttle_time_source_type=self.get_clock())

    def _now_ns(self) -> int:
        # The node clock's reading without building an rclpy Time: it is read for every sample.
        handle = self._clock_handle
        with handle:
            return int(handle.get_now().nanoseconds)

    def _on_watchdog(self) -> None:
        if not self.active:
            return
        now = self._now_ns()
        steady = self.steady_clock()
        for loop in self.loops:
            state = loop.gate.watchdog(now, steady)
            if state == 'lost':
                self._warn(f'{loop.joint}: no valid feedback for '
                           f'{loop.gate.silence_ns(now, steady) * 1e-9:.2f} s; valve '
                           'closed')
            if state != 'fed':
                loop.close_valve()

    def _statuses(self, now_ns: int) -> list[tuple[str, HealthStatus]]:
        return [(loop.joint, joint_health(loop.snapshot(now_ns, self.active)))
                for loop in self.loops]

    # Set-points and trajectories.
    def _on_setpoint(self, message: Float64, loop: JointLoop | None = None) -> None:
        loop = loop or self.loops[0]
        self.setpoints_received += 1
        value = float(message.data)
        if not math.isfinite(value):
            self._warn(f'{loop.joint}: refused a non-finite set-point; keeping '
                       f'{loop.setpoint}')
            return
        loop.setpoint = self._safe_setpoint(loop, math.degrees(value))
        loop.following = False

    def _safe_setpoint(self, loop: JointLoop, setpoint: float) -> float:
        limits = loop.model.angle_limits
        safe = clamp_setpoint(setpoint, limits, self.setpoint_margin)
        loop.clamped = safe != setpoint
        if loop.clamped:
            self._warn(f'{loop.joint}: set-point {setpoint:.2f} deg is beyond the end stops '
                       f'{list(limits or ())} less the margin {self.setpoint_margin:g} deg; '
                       f'using {safe:.2f} deg')
        return safe

    def _on_trajectory(self, message: TrajectoryMessage) -> None:
        self.trajectories_received += 1
        try:
            assert self.trajectories is not None
            self.trajectories.take(message, self._now_ns() * 1e-9, self.setpoint_margin,
                                   self.active)
        except DataError as error:
            self.trajectories_refused += 1
            self.get_logger().warning(str(error))

    # Parameters: checked whole by _check_request, then applied by the handlers below.
    def _check_request(self, request: ParameterRequest) -> None:
        margin = request.number('setpoint_margin', self.parameters.double('setpoint_margin'))
        for loop in self.loops:
            loop.candidate(request)
            setpoint_range(loop.model.angle_limits, margin)

    def _apply_joints(self, request: ParameterRequest) -> None:
        for loop in self.loops:
            for change in loop.apply(loop.candidate(request)):
                self.get_logger().info(change)

    def _apply_feedback_timeout(self) -> None:
        self.feedback_timeout = self.parameters.double('feedback_timeout')
        timeout_ns = seconds_to_ns(self.feedback_timeout)
        for loop in self.loops:
            loop.gate.timeout_ns = timeout_ns
        if self.interfaces is not None:
            self.interfaces.set_timeout(timeout_ns)
        if self.parameters.live:
            self.get_logger().info(f'feedback_timeout now {self.feedback_timeout:g} s')

    def _apply_setpoint_margin(self) -> None:
        self.setpoint_margin = self.parameters.double('setpoint_margin')
        for loop in self.loops:
            loop.allowed = setpoint_range(loop.model.angle_limits, self.setpoint_margin)
            if loop.setpoint is not None:
                loop.setpoint = self._safe_setpoint(loop, loop.setpoint)

    def _apply_stop_band(self) -> None:
        self.stop_band = self.parameters.double('stop_band')
        for loop in self.loops:
            loop.stop_hold.band = self.stop_band

    def _apply_feedback_margin(self) -> None:
        self.feedback_margin = self.parameters.double('feedback_margin')
        for loop in self.loops:
            loop.plausibility.margin = self.feedback_margin

    def _apply_feedforward(self) -> None:
        self.feedforward = self.parameters.flag('feedforward')


def main(args: list[str] | None = None) -> None:
    """Run :class:`PipControllerNode` until shutdown (console script ``controller_node``)."""
    run_node(PipControllerNode, args)

"""
The PIP-IDZ controller as a ROS lifecycle node (``ros2 run hydro_sdp controller_node``).

One node controls one joint (``model_file``, ``controller_file``) or several
(``joints`` with ``model_files`` and ``controller_files`` in the same order; an
empty controller file name designs from the model). Per joint it subscribes to
``<joint>/setpoint`` (rad) and publishes ``<joint>/valve_command`` and
``<joint>/controller_state`` (the layout of
:data:`~hydro_sdp.ros.conversions.CONTROLLER_STATE_LABELS`); one ``joint_states``
feeds every joint, and ``joint_trajectory`` (``trajectory_msgs/JointTrajectory``)
moves the set-points as :mod:`~hydro_sdp.core.control.trajectory` says, with the set-point
rate fed forward through the IDZ when ``feedforward`` is true (a trajectory is
refused whole, with a warning naming the offenders, if it names a joint not
controlled or leaves the end stops less ``setpoint_margin``, or if the node is not
active or has had no feedback from a joint it names). ``/diagnostics``
gets one status per joint every ``diagnostic_period`` (:mod:`~hydro_sdp.core.control.health`).

The core :class:`~hydro_sdp.core.control.pip_controller.PipIdzController` does the
control and the core :mod:`~hydro_sdp.core.control.scheduling` decides when: the first
JointState sample at or after each control instant is controlled (so the
feedback-to-command latency is the computation time); a duplicate or
out-of-order sample is ignored; a sample that cannot be used (NaN, joint
missing, arrays of different lengths, stamp further than ``feedback_timeout``
from the node's clock) is refused for that joint with a throttled warning and its
valve is closed; if no valid feedback arrives for ``feedback_timeout`` the
watchdog closes the valve, and control resumes from the next valid sample
without a bump. Set-points are kept ``setpoint_margin`` degrees inside the end
stops (:mod:`~hydro_sdp.core.control.safety`).

Lifecycle: configure loads the files and designs, and declares the joints'
parameters; activate starts commanding (every joint first holds where it is
found); deactivate closes every valve once and stops commanding; cleanup undoes
configure. With ``autostart`` (the default) the node configures and activates
itself at start.

Every writable parameter applies at run time: ``<joint>.gains.k_i``,
``<joint>.idz.dead_zone``... per joint (with one joint also under the plain names
``gains.k_i``, ``idz.dead_zone``..., kept in step). With a table IDZ (the map's own
inverse) a new ``idz.dead_zone`` shifts the branch of the edge that moved and a new
``idz.slopes`` scales a branch's increments (its chord slope to two thirds of its
largest increment). A change request is checked as
a whole before anything is applied and applied in the post-set callback.

"""

from __future__ import annotations

import math
from typing import Any

from hydro_sdp.core.control.safety import clamp_setpoint, SETPOINT_MARGIN, setpoint_range
from hydro_sdp.core.control.scheduling import seconds_to_ns, watchdog_period_ns
from hydro_sdp.core.control.trajectory import check_trajectory, start_time, TrajectorySampler
from hydro_sdp.core.errors import ConfigurationError, DataError, HydroSdpError
from hydro_sdp.io.model_files import default_model_path
from hydro_sdp.ros.controller_setup import ControllerSetup
from hydro_sdp.ros.conversions import fill_controller_state, joint_angle, trajectory_from_message
from hydro_sdp.ros.first_joint import first_joint
from hydro_sdp.ros.joint_loop import JointLoop
from hydro_sdp.ros.params import declare, value_of
from hydro_sdp.ros.runner import run_node
from rclpy.lifecycle import LifecycleNode, LifecycleState, TransitionCallbackReturn
from rclpy.parameter import Parameter
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64
from trajectory_msgs.msg import JointTrajectory as TrajectoryMessage

SUCCESS = TransitionCallbackReturn.SUCCESS


class PipControllerNode(ControllerSetup, LifecycleNode):
    """
    PIP-IDZ control of one or several joints from ``joint_states``, set-points and trajectories.

    Parameters
    ----------
    node_name : str
        ROS node name.
    **kwargs : Any
        Forwarded to :class:`rclpy.lifecycle.LifecycleNode` (``context``...).

    """

    def __init__(self, *, node_name: str = 'pip_controller', **kwargs: Any) -> None:
        LifecycleNode.__init__(self, node_name, **kwargs)
        self.files = {
            'model_file': declare(self, 'model_file', str(default_model_path()),
                                  'model file of the joint', read_only=True),
            'controller_file': declare(self, 'controller_file', '',
                                       'controller file from hydro-sdp design (default: '
                                       'designed from the model at configuration)',
                                       read_only=True),
            'joints': declare(self, 'joints', Parameter.Type.STRING_ARRAY,
                              'joints of one node, in JointState (overrides model_file)',
                              read_only=True),
            'model_files': declare(self, 'model_files', Parameter.Type.STRING_ARRAY,
                                   'model file of each of the joints', read_only=True),
            'controller_files': declare(self, 'controller_files', Parameter.Type.STRING_ARRAY,
                                        "controller file of each of the joints ('': designed "
                                        'from the model)', read_only=True)}
        declare(self, 'control_period', 0.05, 'control period when designing from a model, s',
                low=1e-3, high=10.0, read_only=True)
        self.feedback_timeout = declare(self, 'feedback_timeout', 0.5,
                                        'watchdog: close the valve after this long without '
                                        'valid feedback, s', low=1e-3, high=60.0)
        self.setpoint_margin = declare(self, 'setpoint_margin', SETPOINT_MARGIN,
                                       'set-points are kept this far inside the end stops, deg',
                                       low=0.0, high=90.0)
        self.feedforward = declare(self, 'feedforward', True,
                                   'feed the set-point rate of trajectories forward')
        self.diagnostic_period = declare(self, 'diagnostic_period', 1.0,
                                         'time between /diagnostics reports, s', low=0.01,
                                         high=60.0, read_only=True)
        autostart = declare(self, 'autostart', True,
                            'configure and activate at start', read_only=True)
        self.loops: list[JointLoop] = []
        self.active = False
        self.samples = 0
        self.outputs = 0
        self.refused = 0
        self.setpoints_received = 0
        self.trajectories_received = 0
        self.trajectories_refused = 0
        self._sampler: TrajectorySampler | None = None
        self._entities: list[Any] = []
        self._configure_error: HydroSdpError | None = None
        self._clock_handle = self.get_clock().handle
        self.add_on_set_parameters_callback(self._check_parameters)
        self.add_post_set_parameters_callback(self._apply_parameters)
        if autostart:
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
    _setpoint = first_joint('loops', 'setpoint', "The first joint's set-point, or None.")
    _blind = first_joint('loops', 'gate.blind', 'Whether the watchdog found no valid feedback '
                         '(the valve is closed).')

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
            self.loops = self.build_loops(self._now_ns())
        except (HydroSdpError, OSError) as error:
            self._configure_error = error if isinstance(error, HydroSdpError) \
                else ConfigurationError(str(error))
            self.loops = []
            self.get_logger().error(f'configuration failed: {error}')
            return TransitionCallbackReturn.FAILURE
        self._sampler = TrajectorySampler({loop.joint: 0.0 for loop in self.loops})
        self.create_interfaces()
        return SUCCESS

    def on_activate(self, state: LifecycleState) -> TransitionCallbackReturn:
        """Start commanding; every joint holds where the next sample finds it."""
        now = self._now_ns()
        for loop in self.loops:
            loop.reset(now)
        self._sampler = TrajectorySampler({loop.joint: 0.0 for loop in self.loops})
        self.active = True
        return SUCCESS

    def on_deactivate(self, state: LifecycleState) -> TransitionCallbackReturn:
        """Close every valve once and stop commanding."""
        self.active = False
        for loop in self.loops:
            self._close_valve(loop)
        return SUCCESS

    def on_cleanup(self, state: LifecycleState) -> TransitionCallbackReturn:
        """Undo configure."""
        self.destroy_interfaces()
        return SUCCESS

    def on_shutdown(self, state: LifecycleState) -> TransitionCallbackReturn:
        """Close the valves if commanding, and release everything."""
        if self.active:
            self.on_deactivate(state)
        if self.loops:
            self.destroy_interfaces()
        return SUCCESS

    def state_label(self) -> str:
        """Return the lifecycle state's label (``active``, ``inactive``...)."""
        return str(self._state_machine.current_state[1])

    # Control.
    def _warn(self, text: str) -> None:
        self.get_logger().warning(text, throttle_duration_sec=1.0,
                                  throttle_time_source_type=self.get_clock())

    def _now_ns(self) -> int:
        # The node clock's reading without building an rclpy Time: it is read for every sample.
        handle = self._clock_handle
        with handle:
            return int(handle.get_now().nanoseconds)

    def _close_valve(self, loop: JointLoop) -> None:
        loop.last_command = loop.rest
        loop.command_pub.publish(Float64(data=float(loop.rest)))
        loop.schedule.hold()

    def _on_setpoint(self, message: Float64, loop: JointLoop | None = None) -> None:
        loop = loop or self.loops[0]
        self.setpoints_received += 1
        value = float(message.data)
        if not math.isfinite(value):
            self._warn(f'{loop.joint}: refused a non-finite set-point; keeping {loop.setpoint}')
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

    def _on_state(self, message: JointState) -> None:
        # Every sample comes through here: the rare paths (refusals, warnings) go to methods.
        self.samples += 1
        if not self.active:
            return
        for loop in self.loops:
            self._control(loop, message)

    def _control(self, loop: JointLoop, message: JointState) -> None:
        try:
            stamp, angle = joint_angle(message, loop.joint)
            admission = loop.gate.admit(stamp, self._now_ns())
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
            setpoint, feedforward = self._follow(loop, stamp * 1e-9)
        elif loop.setpoint is not None:
            setpoint = loop.setpoint
        else:
            setpoint = loop.setpoint = angle   # hold where the joint is until told otherwise
        try:
            u, command = controller.step(setpoint, angle, feedforward)
        except HydroSdpError as error:
            self._warn(f'{loop.joint}: controller refused the sample ({error}); valve closed')
            self._close_valve(loop)
            return
        loop.last_command = command
        loop.last_setpoint = setpoint
        loop.command_pub.publish(Float64(data=float(command)))
        self.outputs += 1
        schedule.stepped(stamp)
        # After the command, so it adds nothing to the feedback-to-command latency; skipped
        # (serialisation and all) while nobody listens.
        state_pub = loop.state_pub
        if state_pub.get_subscription_count():
            state_pub.publish(fill_controller_state(self._state_message, setpoint, angle,
                                                    u, command))

    def _follow(self, loop: JointLoop, t: float) -> tuple[float, float | None]:
        """Return the set-point (deg) and feed-forward (deg per control sample) at ``t`` (s)."""
        sampler = self._sampler
        assert sampler is not None
        setpoint = sampler.setpoint(loop.joint, t)
        if not self.feedforward:
            return setpoint, None
        return setpoint, sampler.feedforward(loop.joint, t, loop.spec.control_period,
                                             loop.spec.delay_samples)

    def _refuse(self, loop: JointLoop, error: DataError) -> None:
        self.refused += 1
        loop.refused_since_report += 1
        self._warn(f'{loop.joint}: refused feedback ({error}); valve closed')
        self._close_valve(loop)

    def _ignore(self, loop: JointLoop, stamp: int) -> None:
        # A duplicate or a sample overtaken by a newer one: the command in force was
        # computed from fresher feedback, so it stays; the sample is only dropped.
        self.refused += 1
        self._warn(f'{loop.joint}: ignored JointState stamp {stamp * 1e-9:.6f} s: it is not '
                   f'after the last one ({(loop.gate.last_stamp or 0) * 1e-9:.6f} s)')

    def _on_watchdog(self) -> None:
        if not self.active:
            return
        now = self._now_ns()
        for loop in self.loops:
            state = loop.gate.watchdog(now)
            if state == 'lost':
                self._warn(f'{loop.joint}: no valid feedback for '
                           f'{loop.gate.silence_ns(now) * 1e-9:.2f} s; valve closed')
            if state != 'fed':
                self._close_valve(loop)

    def _on_trajectory(self, message: TrajectoryMessage) -> None:
        self.trajectories_received += 1
        try:
            trajectory, stamp = trajectory_from_message(message)
            check_trajectory(trajectory, {loop.joint: loop.model.angle_limits
                                          for loop in self.loops}, self.setpoint_margin)
            loops = [self.loop(name) for name in trajectory.joint_names]
            waiting = [loop.joint for loop in loops if loop.setpoint is None and
                       not loop.following]
            if not self.active or waiting:
                raise DataError('trajectory refused: ' + (
                    f"no feedback yet from {', '.join(waiting)}" if self.active
                    else 'the controller is not active'))
        except DataError as error:
            self.trajectories_refused += 1
            self.get_logger().warning(str(error))
            return
        sampler = self._sampler
        assert sampler is not None
        now = self._now_ns() * 1e-9
        start = start_time(stamp, now)
        for loop in loops:
            if not loop.following:
                # Its set-point held until now is the trajectory's anchor.
                assert loop.setpoint is not None
                sampler.hold(loop.joint, loop.setpoint, min(start, now) - 1e-3)
                loop.following = True
                loop.clamped = False
        sampler.replace(trajectory, start)
        sampler.prune(now - 1.0)

    # Parameters.
    def _check_parameters(self, parameters: list[Parameter]) -> Any:
        # On-set: validate the whole request; nothing is applied here.
        try:
            for loop in self.loops:
                loop.candidate(parameters)
                margin = value_of(parameters, 'setpoint_margin', self.setpoint_margin)
                setpoint_range(loop.model.angle_limits, float(margin))
        except (HydroSdpError, TypeError, ValueError) as error:
            return self.parameter_result(False, str(error))
        return self.parameter_result(True)

    def _apply_parameters(self, parameters: list[Parameter]) -> None:
        # Post-set: the request was accepted as a whole; apply all of it.
        names = {parameter.name for parameter in parameters}
        for loop in self.loops:
            for change in loop.apply(loop.candidate(parameters)):
                self.get_logger().info(change)
        if 'feedback_timeout' in names:
            self.feedback_timeout = float(value_of(parameters, 'feedback_timeout', 0.0))
            timeout_ns = seconds_to_ns(self.feedback_timeout)
            for loop in self.loops:
                loop.gate.timeout_ns = timeout_ns
            if self._watchdog is not None:
                self._watchdog.timer_period_ns = watchdog_period_ns(timeout_ns)
            self.get_logger().info(f'feedback_timeout now {self.feedback_timeout:g} s')
        if 'setpoint_margin' in names:
            self.setpoint_margin = float(value_of(parameters, 'setpoint_margin', 0.0))
            for loop in self.loops:
                if loop.setpoint is not None:
                    loop.setpoint = self._safe_setpoint(loop, loop.setpoint)
        if 'feedforward' in names:
            self.feedforward = bool(value_of(parameters, 'feedforward', True))


def main(args: list[str] | None = None) -> None:
    """Run :class:`PipControllerNode` until shutdown (console script ``controller_node``)."""
    run_node(PipControllerNode, args)

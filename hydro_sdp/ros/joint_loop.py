"""One joint of the controller node: its model, design, controller, schedule and parameters."""

from __future__ import annotations

from dataclasses import replace

from hydro_sdp.core.control.controller_spec import ControllerSpec
from hydro_sdp.core.control.health import JointSnapshot
from hydro_sdp.core.control.idz import idz_mode, InverseDeadZone
from hydro_sdp.core.control.idz_table import TableInverseDeadZone
from hydro_sdp.core.control.pip_controller import PipIdzController
from hydro_sdp.core.control.pip_design import PipGains
from hydro_sdp.core.control.plausibility import FeedbackPlausibility
from hydro_sdp.core.control.safety import check_idz_fits, StopHold, top_speeds
from hydro_sdp.core.control.scheduling import ControlSchedule, FeedbackGate, seconds_to_ns
from hydro_sdp.core.model.joint_model import JointModel
from hydro_sdp.ros.parameters.request import ParameterRequest
from hydro_sdp.ros.parameters.spec import ParameterValue
from hydro_sdp.ros.protocols import MessagePublisher
from std_msgs.msg import Float64

IDZ_PARAMETERS = ('idz.dead_zone', 'idz.slopes', 'idz.beta', 'idz.mode', 'idz.fade')
GAIN_PARAMETERS = ('gains.f', 'gains.g', 'gains.k_i')


class JointLoop:
    """
    The control of one joint.

    ``joint``: joint name in JointState and in topic and parameter names.
    ``model``: the joint's model (end stops, valve range).
    ``now_ns``: the node clock's reading, ns.
    ``feedback_margin``: allowance of the feedback checks, degrees
    (:class:`~hydro_sdp.core.control.plausibility.FeedbackPlausibility`).
    ``stop_band``: band of the stop-side hold, degrees
    (:class:`~hydro_sdp.core.control.safety.StopHold`).
    """

    def __init__(self, joint: str, model: JointModel, spec: ControllerSpec, timeout_ns: int,
                 now_ns: int, feedback_margin: float, stop_band: float) -> None:
        self.joint = joint
        self.model = model
        self.spec = spec
        self.prefix = f'{joint}.'
        self.controller = PipIdzController(spec.settings())
        self.rest = spec.idz.rest if spec.idz is not None else 0.0
        self.schedule = ControlSchedule(seconds_to_ns(spec.control_period))
        #: A stamp may lead the node clock by one control period: an earlier command
        #: stays in force no longer than it would anyway.
        self.gate = FeedbackGate(timeout_ns, now_ns, lead_ns=self.schedule.period_ns)
        #: The joint's identified top speeds down and up, deg/s (None: no valve range).
        self.top_speeds = top_speeds(model)
        self.plausibility = FeedbackPlausibility(
            model.angle_limits,
            None if self.top_speeds is None else max(-self.top_speeds[0], self.top_speeds[1]),
            feedback_margin)
        self.stop_hold = StopHold(stop_band)
        #: Allowed set-points, degrees: the stops less the margin (set by the node).
        self.allowed: tuple[float, float] | None = None
        #: Step set-point in force, degrees (None: hold where the joint is at the next sample).
        self.setpoint: float | None = None
        #: Whether the set-point follows a trajectory (then fed forward).
        self.following = False
        self.clamped = False
        self.angle: float | None = None
        self.last_setpoint: float | None = None
        self.last_command = self.rest
        self.refused_since_report = 0
        #: Where the valve commands go (set by the node when it creates its topics).
        self.command_pub: MessagePublisher | None = None
        #: Where each control step is reported (``<joint>/controller_state``).
        self.state_pub: MessagePublisher | None = None
        # One command message, filled and published for every step (publish serialises it).
        self._command = Float64()

    def publish_command(self, command: float) -> None:
        """Send ``command`` to the valve and remember it."""
        self.last_command = command
        message = self._command
        message.data = float(command)
        assert self.command_pub is not None
        self.command_pub.publish(message)

    def close_valve(self) -> None:
        """Send the rest command; the next step starts from rest."""
        self.publish_command(self.rest)
        self.schedule.hold()

    def reset(self, now_ns: int) -> None:
        """Forget set-points and feedback (on activation): hold where the joint is found."""
        self.setpoint = None
        self.following = False
        self.clamped = False
        self.gate = FeedbackGate(self.gate.timeout_ns, now_ns, lead_ns=self.gate.lead_ns)
        self.plausibility.reset()
        self.stop_hold.holding = False
        self.schedule.hold()
        self.refused_since_report = 0

    def parameter_defaults(self) -> dict[str, ParameterValue | None]:
        """Return the current value of each run-time parameter, by name under the joint."""
        gains = self.spec.gains
        values: dict[str, ParameterValue | None] = {
            'gains.f': list(gains.f), 'gains.g': list(gains.g) or None, 'gains.k_i': gains.k_i}
        idz = self.spec.idz
        if idz is not None:
            values.update({'idz.dead_zone': list(idz.dead_zone), 'idz.slopes': list(idz.slopes),
                           'idz.beta': idz.beta, 'idz.mode': idz.mode, 'idz.fade': idz.fade})
        return values

    def candidate(self, request: ParameterRequest) -> ControllerSpec:
        """
        Return the spec a set request would give; raises if it is not valid.

        ``request``: the request (names under the joint, ``<joint>.gains.k_i``...).
        Returns: the spec after the request (this loop's own if it names none of its parameters).
        """
        prefix = self.prefix
        names = {name[len(prefix):] for name in request.names if name.startswith(prefix)}
        spec = self.spec
        if names & set(IDZ_PARAMETERS) and spec.idz is not None:
            idz = self._idz(request)
            if (idz.dead_zone, idz.slopes) != (spec.idz.dead_zone, spec.idz.slopes):
                check_idz_fits(idz, self.model, spec.control_period, spec.v_limits)
            spec = replace(spec, idz=idz)
        if names & set(GAIN_PARAMETERS):
            gains = spec.gains
            spec = replace(spec, gains=PipGains(    # checks orders and closed-loop stability
                f=request.numbers(prefix + 'gains.f', gains.f),
                g=request.numbers(prefix + 'gains.g', gains.g),
                k_i=request.number(prefix + 'gains.k_i', gains.k_i)))
        return spec

    def _idz(self, request: ParameterRequest) -> InverseDeadZone | TableInverseDeadZone:
        prefix = self.prefix
        current = self.spec.idz
        assert current is not None
        edges = request.pair(prefix + 'idz.dead_zone', current.dead_zone)
        slopes = request.pair(prefix + 'idz.slopes', current.slopes)
        beta = request.number(prefix + 'idz.beta', current.beta)
        mode = idz_mode(request.text(prefix + 'idz.mode', current.mode))
        fade = request.number(prefix + 'idz.fade', current.fade)
        if isinstance(current, TableInverseDeadZone):
            # A table keeps its shape: new slopes scale a branch, new edges shift it.
            idz = current
            if slopes != current.slopes:
                idz = idz.with_slopes(slopes)
            if edges != current.dead_zone:
                idz = idz.with_edges(edges)
            return replace(idz, beta=beta, mode=mode, fade=fade)
        return InverseDeadZone(dead_zone=edges, slopes=slopes, beta=beta, mode=mode,
                               rest=current.rest, fade=fade)

    def apply(self, spec: ControllerSpec) -> list[str]:
        """Use ``spec`` from now on; return what changed, for the log."""
        changes = []
        if spec.idz is not None and spec.idz != self.spec.idz:
            self.controller.update_idz(spec.idz)
            changes.append(f'{self.joint}: IDZ now edges {list(spec.idz.dead_zone)}, slopes '
                           f"[{', '.join(f'{s:.4g}' for s in spec.idz.slopes)}]")
        if spec.gains != self.spec.gains:
            self.controller.update_gains(spec.gains)
            changes.append(f'{self.joint}: gains now f {list(spec.gains.f)}, '
                           f'g {list(spec.gains.g)}, kI {spec.gains.k_i}')
        self.spec = spec
        return changes

    def snapshot(self, now_ns: int, active: bool) -> JointSnapshot:
        """Return the joint's state for ``/diagnostics`` and reset the refusal count."""
        refused, self.refused_since_report = self.refused_since_report, 0
        gate = self.gate
        age = None if gate.last_stamp is None else max(gate.silence_ns(now_ns), 0) * 1e-9
        idz = self.spec.idz
        return JointSnapshot(
            joint=self.joint, feedback_age=age,
            stale_after=max(2.0 * self.spec.control_period, 0.5 * self.gate.timeout_ns * 1e-9),
            watchdog_closed=self.gate.blind, refused=refused, clamped=self.clamped,
            active=active, setpoint=self.last_setpoint, angle=self.angle,
            command=self.last_command, idz_edges=None if idz is None else idz.dead_zone)

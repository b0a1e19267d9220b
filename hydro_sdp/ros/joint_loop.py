"""
One joint of the controller node: its model, design, controller, schedule and parameters.

The node (:mod:`hydro_sdp.ros.controller_node`) holds one :class:`JointLoop` per
joint and wires them to ROS; a loop knows its run-time parameters by their
name under the joint (``<joint>.gains.k_i``, ``<joint>.idz.dead_zone``...) and
builds the spec a set request would give (:meth:`JointLoop.candidate`).

"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

from hydro_sdp.core.control.controller_spec import ControllerSpec
from hydro_sdp.core.control.health import JointSnapshot
from hydro_sdp.core.control.idz import idz_mode, IDZ_MODES, InverseDeadZone
from hydro_sdp.core.control.idz_table import TableInverseDeadZone
from hydro_sdp.core.control.pip_controller import PipIdzController
from hydro_sdp.core.control.pip_design import PipGains
from hydro_sdp.core.control.scheduling import ControlSchedule, FeedbackGate, seconds_to_ns
from hydro_sdp.core.model.joint_model import JointModel
from hydro_sdp.ros.params import pair, value_of
from rclpy.parameter import Parameter

IDZ_PARAMETERS = ('idz.dead_zone', 'idz.slopes', 'idz.beta', 'idz.mode')
GAIN_PARAMETERS = ('gains.f', 'gains.g', 'gains.k_i')

#: Description and range of each run-time parameter of a joint, by name under the joint.
PARAMETERS: dict[str, tuple[str, float | None, float | None]] = {
    'gains.f': ('PIP output feedback gains f0.., (deg per control sample) per deg', None, None),
    'gains.g': ('PIP input feedback gains g1.. (dimensionless)', None, None),
    'gains.k_i': ('PIP integral gain kI, (deg per control sample) per deg of error', 0.0, 10.0),
    'idz.dead_zone': ('IDZ edges, input units (a table: each branch moves with its edge)',
                      None, None),
    'idz.slopes': ('IDZ slopes, deg per control sample per input unit (a table: chord slopes '
                   'to two thirds of its largest increment; a new value scales the branch)',
                   None, None),
    'idz.beta': ('IDZ chatter band, deg per control sample', 0.0, 100.0),
    'idz.mode': (f"IDZ mode: {', '.join(IDZ_MODES)}", None, None),
}


class JointLoop:
    """
    The control of one joint.

    Parameters
    ----------
    joint : str
        Joint name in JointState and in topic and parameter names.
    model : JointModel
        The joint's model (end stops, valve range).
    spec : ControllerSpec
        The controller design.
    timeout_ns : int
        Feedback watchdog timeout, ns.
    now_ns : int
        The node clock's reading, ns.

    """

    def __init__(self, joint: str, model: JointModel, spec: ControllerSpec, timeout_ns: int,
                 now_ns: int) -> None:
        self.joint = joint
        self.model = model
        self.spec = spec
        self.prefix = f'{joint}.'
        self.controller = PipIdzController(spec.settings())
        self.rest = spec.idz.rest if spec.idz is not None else 0.0
        self.schedule = ControlSchedule(seconds_to_ns(spec.control_period))
        self.gate = FeedbackGate(timeout_ns, now_ns)
        #: Step set-point in force, degrees (None: hold where the joint is at the next sample).
        self.setpoint: float | None = None
        #: Whether the set-point follows a trajectory (then fed forward).
        self.following = False
        self.clamped = False
        self.angle: float | None = None
        self.last_setpoint: float | None = None
        self.last_command = self.rest
        self.refused_since_report = 0
        # Set by the node: ROS publishers and subscriptions of this joint.
        self.command_pub: Any = None
        self.state_pub: Any = None
        self.setpoint_sub: Any = None

    def reset(self, now_ns: int) -> None:
        """Forget set-points and feedback (on activation): hold where the joint is found."""
        self.setpoint = None
        self.following = False
        self.clamped = False
        self.gate = FeedbackGate(self.gate.timeout_ns, now_ns)
        self.schedule.hold()
        self.refused_since_report = 0

    def parameter_defaults(self) -> dict[str, Any]:
        """Return the current value of each run-time parameter, by name under the joint."""
        gains = self.spec.gains
        values: dict[str, Any] = {
            'gains.f': list(gains.f),
            'gains.g': list(gains.g) or Parameter.Type.DOUBLE_ARRAY,
            'gains.k_i': gains.k_i}
        idz = self.spec.idz
        if idz is not None:
            values.update({'idz.dead_zone': list(idz.dead_zone), 'idz.slopes': list(idz.slopes),
                           'idz.beta': idz.beta, 'idz.mode': idz.mode})
        return values

    def candidate(self, parameters: list[Parameter]) -> ControllerSpec:
        """
        Return the spec a set request would give; raises if it is not valid.

        Parameters
        ----------
        parameters : list of Parameter
            The request (names under the joint, ``<joint>.gains.k_i``...).

        Returns
        -------
        ControllerSpec
            The spec after the request (this loop's own if it names none of its parameters).

        """
        prefix = self.prefix
        names = {p.name[len(prefix):] for p in parameters if p.name.startswith(prefix)}
        spec = self.spec

        def new(name: str, current: Any) -> Any:
            return value_of(parameters, prefix + name, current)
        if names & set(IDZ_PARAMETERS) and spec.idz is not None:
            current = spec.idz
            edges = pair(new('idz.dead_zone', current.dead_zone), prefix + 'idz.dead_zone')
            slopes = pair(new('idz.slopes', current.slopes), prefix + 'idz.slopes')
            beta = float(new('idz.beta', current.beta))
            mode = idz_mode(new('idz.mode', current.mode))
            idz: InverseDeadZone | TableInverseDeadZone
            if isinstance(current, TableInverseDeadZone):
                # A table keeps its shape: new slopes scale a branch, new edges shift it.
                idz = current
                if slopes != current.slopes:
                    idz = idz.with_slopes(slopes)
                if edges != current.dead_zone:
                    idz = idz.with_edges(edges)
                idz = replace(idz, beta=beta, mode=mode)
            else:
                idz = InverseDeadZone(dead_zone=edges, slopes=slopes, beta=beta, mode=mode,
                                      rest=current.rest)
            spec = replace(spec, idz=idz)    # checks the IDZ against the valve range
        if names & set(GAIN_PARAMETERS):
            gains = spec.gains
            spec = replace(spec, gains=PipGains(    # checks orders and closed-loop stability
                f=tuple(float(x) for x in new('gains.f', gains.f)),
                g=tuple(float(x) for x in new('gains.g', gains.g) or ()),
                k_i=float(new('gains.k_i', gains.k_i))))
        return spec

    def apply(self, spec: ControllerSpec) -> list[str]:
        """Use ``spec`` from now on; return what changed, for the log."""
        changes = []
        if spec.idz is not None and spec.idz != self.spec.idz:
            self.controller.update_idz(spec.idz)
            changes.append(f'{self.joint}: IDZ now edges {list(spec.idz.dead_zone)}, slopes '
                           f'{[round(s, 4) for s in spec.idz.slopes]}')
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

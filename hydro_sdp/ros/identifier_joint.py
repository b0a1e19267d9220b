"""One joint of the identifier node: its estimator, recalibration decision and topics."""

from __future__ import annotations

from dataclasses import asdict
import math
from typing import Protocol

from hydro_sdp.core.control.health import JointSnapshot
from hydro_sdp.core.control.idz_design import default_form, IdzForm
from hydro_sdp.core.control.idz_recalibration import Decision, Recalibration, RecalibrationPolicy
from hydro_sdp.core.identification.online import SdpEstimate
from hydro_sdp.core.identification.online_edges import EdgeEstimate
from hydro_sdp.core.model.joint_model import JointModel
from hydro_sdp.ros.protocols import MessagePublisher
from rcl_interfaces.msg import Parameter as ParameterMessage, ParameterType, ParameterValue
from rclpy.task import Future


class OnlineEstimator(Protocol):
    """What the node needs of an online estimator (tests put a stand-in with a set estimate)."""

    @property
    def delay(self) -> int:
        """Return the delay, samples."""

    def update(self, v: float, y: float) -> bool:
        """Take the command in force and the measured angle of one sample."""

    def named_estimate(self) -> SdpEstimate | EdgeEstimate:
        """Return the estimates with their standard deviations."""

    def estimate(self) -> JointModel:
        """Return the estimate as a joint model."""


#: Units of the estimates, by the start of their names.
UNITS = {'dead_zone': 'input units', 'saturation': 'deg/s', 'curvature': '1/input unit',
         'speed_scale': "times the model's speed"}


def estimate_topics(estimate: SdpEstimate | EdgeEstimate) -> dict[str, float]:
    """
    Return the estimate as topic values: saturation speeds in rad/s, the rest as they are.

    ``estimate``: the estimate (speeds in deg/s).
    Returns: value by topic name under ``<joint>/sdp/``.
    """
    values = {}
    for name, value in asdict(estimate).items():
        if name.startswith('saturation_'):
            base, std = (name[:-4], '_std') if name.endswith('_std') else (name, '')
            name, value = f'{base}_rad_s{std}', math.radians(value)
        values[name] = float(value)
    return values


def estimate_pairs(estimate: SdpEstimate | EdgeEstimate) -> dict[str, tuple[float, float]]:
    """Return each estimated value with its standard deviation, by name with its unit."""
    values = asdict(estimate)
    pairs = {}
    for name, value in values.items():
        if name.endswith('_std'):
            continue
        unit = next(u for prefix, u in UNITS.items() if name.startswith(prefix))
        pairs[f'{name} [{unit}]'] = (float(value), float(values[f'{name}_std']))
    return pairs


def double_array(name: str, values: tuple[float, ...]) -> ParameterMessage:
    """Return a double-array parameter message."""
    return ParameterMessage(name=name, value=ParameterValue(
        type=ParameterType.PARAMETER_DOUBLE_ARRAY, double_array_value=[float(v) for v in values]))


class IdentifiedJoint:
    """
    The online identification of one joint.

    ``joint``: joint name in JointState, topics, and the controller's parameters.
    """

    def __init__(self, joint: str, model: JointModel, estimator: OnlineEstimator,
                 policy: RecalibrationPolicy) -> None:
        self.joint = joint
        self.model = model
        self.estimator = estimator
        #: The form of the controller's IDZ the slopes are for: the model family's default.
        self.form: IdzForm = default_form(model)
        # The IDZ edges the controller uses: those of the model it was designed from.
        self.recalibration = Recalibration(estimator.named_estimate().edges, policy)
        self.recalibrations = 0
        #: Times of the accepted recalibrations (their requests), s of the node clock.
        self.recalibration_times: list[float] = []
        self.last_decision: Decision | None = None
        self.command: float | None = None
        self.angle: float | None = None
        self.last_publish: int | None = None
        self.last_sample_ns: int | None = None
        #: The controller's answer to a recalibration request, while it is awaited.
        self.pending: Future | None = None
        # Set by the node: where the estimates and the recalibration flag go.
        self.estimate_pubs: dict[str, MessagePublisher] = {}
        self.flag_pub: MessagePublisher | None = None

    def parameter_names(self) -> tuple[str, str]:
        """Return the controller's parameters of this joint's IDZ edges and slopes."""
        return f'{self.joint}.idz.dead_zone', f'{self.joint}.idz.slopes'

    def snapshot(self, now_ns: int, stale_after: float) -> JointSnapshot:
        """Return the joint's state for ``/diagnostics``."""
        age = None if self.last_sample_ns is None else max(now_ns - self.last_sample_ns, 0) * 1e-9
        decision = self.last_decision
        return JointSnapshot(
            joint=self.joint, feedback_age=age, stale_after=stale_after,
            recalibration_needed=bool(decision is not None and decision.needed),
            angle=self.angle, command=self.command, idz_edges=self.recalibration.reference,
            estimates=estimate_pairs(self.estimator.named_estimate()))

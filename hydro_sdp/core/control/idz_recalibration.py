"""When the online estimate calls for a new IDZ, and which edges (methods 7.5)."""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass, replace
import math
from typing import Protocol

from hydro_sdp.core.control.idz_design import chord_idz, default_form, IdzForm
from hydro_sdp.core.control.idz_table import Idz
from hydro_sdp.core.control.idz_table_design import table_idz
from hydro_sdp.core.errors import ConfigurationError
from hydro_sdp.core.model.joint_model import JointModel
from hydro_sdp.core.model.static_maps import PowerSatMap, PwlMap, SdpDzMap, SdpMap
from hydro_sdp.core.model.timing import SamplePeriod
from hydro_sdp.core.validation import require_positive_fields


class EdgesEstimate(Protocol):
    """What the decision reads of an estimate: the edges and their standard deviations."""

    @property
    def edges(self) -> tuple[float, float]:
        """Return the dead-zone edges, input units."""

    @property
    def edges_std(self) -> tuple[float, float]:
        """Return their standard deviations, input units."""


@dataclass(frozen=True)
class RecalibrationPolicy:
    """
    Thresholds of the recalibration decision.

    Attributes
    ----------
    significance : float
        Change of an edge, in its standard deviations, that counts as real.
    settle : float
        Time over which an edge estimate must have moved less than its standard deviation, s.
    confidence : float
        Largest edge standard deviation to act on, as a fraction of the estimated dead-zone width.
    min_change : float
        Smallest edge change worth a recalibration, input units.
    cooldown : float
        Least time between recalibrations, s.

    """

    significance: float = 3.0
    settle: float = 2.0
    confidence: float = 0.1
    min_change: float = 0.03
    cooldown: float = 5.0

    def __post_init__(self) -> None:
        require_positive_fields(self, ('significance', 'confidence'))
        require_positive_fields(self, ('settle', 'min_change', 'cooldown'), zero_allowed=True)


@dataclass(frozen=True)
class Decision:
    """
    The outcome for one estimate.

    Parameters
    ----------
    needed : bool
        Some edge differs from the reference significantly and has settled.
    due : bool
        ``needed``, and the cooldown since the last recalibration has passed.
    edges : tuple[float, float]
        The IDZ edges to set: the estimate for the edges that changed, the
        reference for the others, input units.
    z : tuple[float, float]
        Change of each edge from the reference in its standard deviations.

    """

    needed: bool
    due: bool
    edges: tuple[float, float]
    z: tuple[float, float]


class Recalibration:
    """
    The recalibration decision of one joint, fed with successive estimates.

    ``reference``: the IDZ edges the controller uses, input units.
    ``policy``: thresholds; may be replaced at any time (``self.policy = ...``).
    """

    def __init__(self, reference: tuple[float, float],
                 policy: RecalibrationPolicy = RecalibrationPolicy()) -> None:
        self.reference = (float(reference[0]), float(reference[1]))
        self.policy = policy
        self.last_attempt: float | None = None
        self._history: deque[tuple[float, float, float]] = deque()

    def _settled(self, time: float, edge: int, std: float) -> bool:
        # The history starts at or before time - settle; the edge spans less than its std.
        if self._history[0][0] > time - self.policy.settle:
            return False
        values = [entry[1 + edge] for entry in self._history]
        return max(values) - min(values) <= std

    def observe(self, time: float, estimate: EdgesEstimate) -> Decision:
        """
        Take the estimate at ``time`` and decide.

        ``time``: time of the estimate, s (any origin; increasing).
        """
        policy = self.policy
        edges, stds = estimate.edges, estimate.edges_std
        if self._history and time < self._history[-1][0]:
            self._history.clear()                  # time went back (a replayed bag)
        self._history.append((time, edges[0], edges[1]))
        while len(self._history) > 1 and self._history[1][0] <= time - policy.settle:
            self._history.popleft()
        width = edges[1] - edges[0]
        new = list(self.reference)
        z = []
        for edge in (0, 1):
            change = edges[edge] - self.reference[edge]
            std = stds[edge]
            score = abs(change) / std if std > 0.0 else math.inf
            z.append(score if math.isfinite(change) else math.nan)
            if (math.isfinite(change) and math.isfinite(std) and score > policy.significance
                    and abs(change) >= policy.min_change
                    and std <= policy.confidence * width
                    and self._settled(time, edge, std)):
                new[edge] = edges[edge]
        needed = (new[0], new[1]) != self.reference and new[0] < new[1]
        cooled = self.last_attempt is None or time - self.last_attempt >= policy.cooldown
        return Decision(needed=needed, due=needed and cooled, edges=(new[0], new[1]),
                        z=(z[0], z[1]))

    def attempted(self, time: float) -> None:
        """Start the cooldown: a recalibration was requested at ``time`` (s)."""
        self.last_attempt = time

    def accepted(self, edges: tuple[float, float]) -> None:
        """Take the edges the controller accepted as the new reference."""
        self.reference = (float(edges[0]), float(edges[1]))


def with_dead_zone(model: JointModel, edges: tuple[float, float]) -> JointModel:
    """
    Return the model with its dead-zone edges at ``edges``, each side moved with its edge.

    ``model``: a model whose map has explicit edges (``sdp``, ``sdp_dz``, ``power_sat``, or a
    ``pwl`` with a zero plateau).
    ``edges``: the new ``(a3, a6)``, input units.
    """
    low, high = (float(x) for x in edges)
    if not (math.isfinite(low) and math.isfinite(high) and low <= high):
        raise ConfigurationError(f'dead-zone edges must be finite and ordered, got {[low, high]}')
    static_map = model.static_map
    if isinstance(static_map, (SdpMap, SdpDzMap, PowerSatMap)):
        return replace(model, static_map=replace(static_map, dead_zone=(low, high)))
    if isinstance(static_map, PwlMap) and static_map.dead_zone is not None:
        old_low, old_high = static_map.dead_zone
        below = [(k + low - old_low, s) for k, s in zip(static_map.knots, static_map.speeds)
                 if k <= old_low]
        above = [(k + high - old_high, s) for k, s in zip(static_map.knots, static_map.speeds)
                 if k >= old_high]
        if below[-1][0] == above[0][0]:
            above = above[1:]
        points = below + above
        return replace(model, static_map=PwlMap(knots=tuple(p[0] for p in points),
                                                speeds=tuple(p[1] for p in points)))
    raise ConfigurationError(f'the edges of a {model.kind} map without a dead-zone cannot move')


def recalibrated_idz(estimate: JointModel, edges: tuple[float, float],
                     control_period: SamplePeriod, form: IdzForm | None = None) -> Idz:
    """IDZ of the estimated model with the decided edges, at the control period."""
    model = with_dead_zone(estimate, edges)
    form = default_form(estimate) if form is None else form
    if form == 'chord':
        return chord_idz(model, control_period)
    return table_idz(model, control_period, beta=0.0)

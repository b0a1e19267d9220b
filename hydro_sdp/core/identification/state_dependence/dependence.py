"""What the SDP analysis of a joint finds: each parameter against each state (methods 14.6)."""

from __future__ import annotations

from dataclasses import dataclass, field
import math
from typing import Literal

from hydro_sdp.core.arrays import FloatArray
from hydro_sdp.core.identification.state_dependence.backfit import Backfit, TermEstimate
from hydro_sdp.core.model.timing import SamplePeriod
import numpy as np

#: What the gains describe: the SDP-ARX model's ``b``, or the measured increment over
#: the model's.
Target = Literal['arx', 'ratio']
#: Most points of a curve's grid (its distinct values when fewer).
GRID_POINTS = 60


@dataclass(frozen=True, eq=False)
class StateDependence:
    """
    One parameter estimated along one state (one direction of motion).

    Attributes
    ----------
    state : str
        The state (``command``, ``angle``...).
    parameter : str
        ``b`` (SDP-ARX gain), ``a1``, ``ratio`` (measured over modelled increment) or ``residual``
        (measured less modelled increment, deg).
    direction : str
        ``positive`` or ``negative`` (sign of the drive, or of the model's increment), ``both`` for
        a parameter of every sample.
    share : float
        Share of the constant-parameter model's squared residual removed by letting the parameter
        follow the state.
    nvr : float
        NVR of its walk along the state (0: no dependence).
    values : FloatArray
        State value of each group (sorted).
    estimate : FloatArray
        The parameter per group.
    se : FloatArray
        Its standard error per group.
    given : str or None
        The state this dependence is added to (its share is what it adds); None for the first
        state, weighed alone.

    """

    state: str
    parameter: str
    direction: str
    share: float
    nvr: float
    p_value: float
    significant: bool
    values: FloatArray
    estimate: FloatArray
    se: FloatArray
    constant: float
    samples: int
    given: str | None = None

    @classmethod
    def of(cls, state: str, parameter: str, direction: str,
           term: TermEstimate) -> StateDependence:
        """Describe a back-fitted term."""
        return cls(state, parameter, direction, term.share, term.nvr, term.p_value,
                   term.significant, term.values, term.estimate, term.standard_error,
                   term.constant, int(term.ordering.samples.size))

    def grid(self, points: int = GRID_POINTS) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Return ``(state, estimate, se)`` at up to ``points`` groups evenly spread in rank."""
        size = self.values.size
        index = np.arange(size) if size <= points else np.unique(
            np.round(np.linspace(0, size - 1, points)).astype(int))
        return self.values[index], self.estimate[index], self.se[index]

    def at(self, state: FloatArray) -> FloatArray:
        """Return the estimate at state values (linear between groups, held beyond)."""
        return np.interp(np.asarray(state, dtype=np.float64), self.values, self.estimate)


@dataclass(frozen=True)
class ParameterSummary:
    """
    A parameter held constant, and how much it varies with the states.

    Attributes
    ----------
    nvr : float
        Largest NVR of its walk along any state analysed (0: constant along all).

    """

    mean: float
    se: float
    nvr: float


@dataclass(frozen=True, eq=False)
class SdpAnalysis:
    """
    Every parameter of a joint against every candidate state.

    Attributes
    ----------
    target : str
        ``arx`` (the SDP-ARX model) or ``ratio`` (what a model misses).
    delay : int
        Delay ``tau``, samples.
    sample_period : SamplePeriod
        Sample period, s.
    states : tuple[StateDependence, ...]
        The gains (``b`` or ``ratio``) per state and direction, largest share first.
    residual : tuple[StateDependence, ...]
        The increment residual per state (``ratio`` only), largest share first.
    a1 : ParameterSummary or None
        The autoregressive parameter (``arx`` only), paper's sign: -1 for an integrator.
    a1_states : tuple[StateDependence, ...]
        ``a1`` along each state (``arx`` only).
    fits : dict
        The back-fit of each state (keys: state, or ``residual <state>``).
    alone : dict[str, float]
        Held-out share of each state's gains fitted alone (keys: state, or ``residual <state>``),
        before any is weighed given the first.
    left_out : dict[str, int]
        Increments left out because the joint could not move, by reason
        (:data:`~hydro_sdp.core.identification.state_dependence.states.HOLDS`).

    """

    target: Target
    samples: int
    delay: int
    sample_period: SamplePeriod
    rest: float
    states: tuple[StateDependence, ...]
    residual: tuple[StateDependence, ...]
    a1: ParameterSummary | None
    a1_states: tuple[StateDependence, ...]
    fits: dict[str, Backfit]
    skipped: tuple[tuple[str, str], ...] = ()
    alone: dict[str, float] = field(default_factory=dict)
    left_out: dict[str, int] = field(default_factory=dict)

    @property
    def analysed(self) -> tuple[str, ...]:
        """Return the states analysed, in the order of their best share."""
        seen: list[str] = []
        for entry in self.states:
            if entry.state not in seen:
                seen.append(entry.state)
        return tuple(seen)

    def dependence(self, state: str, direction: str | None = None,
                   parameter: str | None = None) -> list[StateDependence]:
        """Return the entries of one state (gains, residual and ``a1``), filtered."""
        entries = self.states + self.residual + self.a1_states
        return [e for e in entries if e.state == state
                and (direction is None or e.direction == direction)
                and (parameter is None or e.parameter == parameter)]

    def state_share(self, state: str) -> float:
        """Return the share of the squared residual the state's gains remove together."""
        return float(sum(e.share for e in self.states if e.state == state))


def ordered(entries: list[StateDependence]) -> tuple[StateDependence, ...]:
    """
    Order entries: the first state's (the one that explains most alone), then the others.

    ``entries`` start with the first state's; within it, and among the others
    (weighed by what they add to it), the largest share comes first (ties:
    significant first, then by name).
    """
    if not entries:
        return ()
    first = entries[0].state

    def key(entry: StateDependence) -> tuple[float, bool, str, str]:
        share = entry.share if math.isfinite(entry.share) else 0.0
        return (-share, not entry.significant, entry.state, entry.direction)
    return tuple(sorted((e for e in entries if e.state == first), key=key)) + tuple(
        sorted((e for e in entries if e.state != first), key=key))

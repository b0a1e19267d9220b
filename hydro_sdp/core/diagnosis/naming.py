"""The data name the effect: SDP analysis of what the model misses (methods 8.3)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Sequence

from hydro_sdp.core.arrays import FloatArray
from hydro_sdp.core.errors import HydroSdpError
from hydro_sdp.core.identification.state_dependence import analyse, SdpAnalysis, StateDependence
from hydro_sdp.core.identification.state_dependence.states import Rows, rows_of
from hydro_sdp.core.model.joint_model import JointModel
from hydro_sdp.core.model.records import Record
import numpy as np

#: A state names its words when its dependence removes at least this share of the squared
#: residual on data it was not fitted to (the analysis's held-out share).
MIN_SHARE = 0.02
#: Most rows analysed (every k-th increment beyond: neighbours at 100 Hz say little more).
MAX_ROWS = 4_000
#: The states analysed, when the records can give them.
STATES = ('command', 'angle', 'since_change', 'reversals', 'others_speed', 'load')


@dataclass(frozen=True, eq=False)
class Naming:
    """
    What the SDP analysis of the model's misses says, state by state.

    Attributes
    ----------
    analysis : SdpAnalysis or None
        The analysis (None when the records could not be analysed).
    shares : dict[str, float]
        Per state analysed: the share of the squared residual its significant dependences remove,
        held out (the larger of the ratio's, summed over the directions, and the residual's; 0 when
        none is significant).
    agreement : float or None
        Correlation of the two directions' ratios along the angle where both are seen: near 1 when
        a factor of the angle is shared, near -1 when it mirrors.
    shared : bool
        Whether the angle's dependence is a factor both directions share: the ratio explains more
        than the residual and the two directions agree (a mirrored factor, gravity-like, adds the
        same offset to both directions' increments, which the residual shows and the ratio's
        per-direction curves mirror).

    """

    analysis: SdpAnalysis | None
    shares: dict[str, float] = field(default_factory=dict)
    agreement: float | None = None
    shared: bool = False
    failure: str = ''

    def named(self, state: str) -> bool:
        """Whether ``state`` names its words."""
        return self.shares.get(state, 0.0) >= MIN_SHARE

    def order(self) -> list[str]:
        """Return the states that name their words, the largest share first."""
        named = [state for state in self.shares if self.named(state)]
        return sorted(named, key=lambda state: -self.shares[state])

    def entries(self, state: str) -> list[StateDependence]:
        """Return the analysis's estimates along ``state`` (ratio per direction, residual)."""
        if self.analysis is None:
            return []
        return [e for e in self.analysis.dependence(state)
                if e.parameter in ('ratio', 'residual')]

    def ratio(self, state: str, direction: str) -> StateDependence | None:
        """Return the ratio's estimate along ``state`` in ``direction``, if analysed."""
        for entry in self.entries(state):
            if entry.parameter == 'ratio' and entry.direction == direction:
                return entry
        return None


def _share(entries: Sequence[StateDependence]) -> float:
    ratio = sum(e.share for e in entries if e.parameter == 'ratio')
    residual = max((e.share for e in entries if e.parameter == 'residual'), default=0.0)
    return float(max(ratio, residual))


def agreement_of(up: StateDependence, down: StateDependence) -> float | None:
    """
    Return the correlation of two directions' ratios along one state where both are seen.

    ``up``, ``down``: the ratio along the state for each direction of motion.
    Returns: correlation of the two curves over 50 points of their common range; None when they
    share too little of it or either is flat.
    """
    low = max(float(up.values[0]), float(down.values[0]))
    high = min(float(up.values[-1]), float(down.values[-1]))
    span = (max(float(up.values[-1]), float(down.values[-1]))
            - min(float(up.values[0]), float(down.values[0])))
    if not high > low or (high - low) < 0.25 * span:
        return None
    grid: FloatArray = np.linspace(low, high, 50)
    a, b = up.at(grid), down.at(grid)
    if np.ptp(a) <= 0.0 or np.ptp(b) <= 0.0:
        return None
    return float(np.corrcoef(a, b)[0, 1])


def scale_share(rows: Rows) -> float:
    """
    Return the share of the squared increment residual a speed scale per direction removes.

    ``rows``: rows of the analysis, with the model's increments.
    Returns: ``1 - sum (dy - c dy^)^2 / sum (dy - dy^)^2`` with ``c`` fitted per direction.
    """
    assert rows.predicted is not None
    measured, predicted = rows.increment, rows.predicted
    residual = measured - predicted
    total = float(np.dot(residual, residual))
    if not total > 0.0:
        return 0.0
    left = total
    for side in (predicted > 0.0, predicted < 0.0):
        x, y = predicted[side], measured[side]
        if x.size:
            scale = float(np.dot(x, y) / np.dot(x, x))
            left += float(np.dot(y - scale * x, y - scale * x) - np.dot(y - x, y - x))
    return max(0.0, 1.0 - left / total)


def name_states(records: Sequence[Record], model: JointModel, *, seed: int = 0) -> Naming:
    """
    Analyse what ``model`` misses on ``records`` against every state they can give.

    Returns: the shares of the states and the angle's agreement.
    """
    try:
        # The held-out share is the evidence: no bootstrap (the candidates get theirs).
        analysis = analyse(records, model=model, states=STATES, replicates=0, seed=seed,
                           max_rows=MAX_ROWS)
    except (HydroSdpError, np.linalg.LinAlgError, ValueError) as error:
        return Naming(None, failure=str(error))
    # A state correlated with another in the data (the angle where every stroke starts,
    # with the time since its command changed) explains little given the other: both
    # name their words by what they explain alone or given the first, whichever is more,
    # and the decision weighs the words' sizes.
    shares = {}
    for state in analysis.analysed:
        weighed = _share([e for e in analysis.dependence(state)
                          if e.parameter in ('ratio', 'residual')])
        alone = max(analysis.alone.get(state, 0.0),
                    analysis.alone.get(f'residual {state}', 0.0))
        shares[state] = min(1.0, max(weighed, alone))
    # The analysis's rows: those where the joint is held at a stop or stalled left out.
    rows = rows_of(records, analysis.delay, analysis.rest, model, analysis.sample_period,
                   holds=True).free()[0]
    shares['command'] = min(1.0, max(shares.get('command', 0.0), scale_share(rows)))
    up = next((e for e in analysis.dependence('angle', 'positive', 'ratio')), None)
    down = next((e for e in analysis.dependence('angle', 'negative', 'ratio')), None)
    agreement = agreement_of(up, down) if up is not None and down is not None else None
    angle = analysis.dependence('angle')
    ratio = sum(e.share for e in angle if e.parameter == 'ratio')
    residual = max((e.share for e in angle if e.parameter == 'residual'), default=0.0)
    shared = agreement is not None and agreement > 0.0 and ratio >= residual
    return Naming(analysis, shares, agreement, shared)

"""What the discrepancy workflow returns: candidates, ledger and evidence (methods 8.4)."""

from __future__ import annotations

from dataclasses import dataclass, field
import math
from typing import Literal, Sequence

from hydro_sdp.core.arrays import FloatArray, IntArray
from hydro_sdp.core.identification.state_dependence import StateDependence
from hydro_sdp.core.model.joint_model import JointModel
from hydro_sdp.core.model.timing import SamplePeriod
import numpy as np

#: What a residual signature is drawn against: the delayed command or the angle (residual
#: averaged in bins), or the samples after command changes or reversals (event average), or
#: the other joints' summed speed (averaged in bins).
Feature = Literal['command', 'angle', 'events', 'reversals', 'others']


@dataclass(frozen=True)
class Candidate:
    """
    One effect tried on the data.

    Attributes
    ----------
    applicable : bool
        Whether the effect can be added to this model at all.
    gain : float
        Share of the squared velocity residual the effect removes on the held-out runs (on the
        estimation runs until it is judged).
    t : float
        Standard score of that reduction under the block bootstrap's null.
    significant : bool
        Whether the reduction is significant (``p_value`` <= 0.01).
    signature_match : bool
        Whether the data show the effect's own signature, which no other word explains (reported;
        the ranking is by held-out gain alone).
    held_out : float
        Share of the windowed simulation error on the held-out runs it removes; once accepted, over
        the samples all accepted candidates share (what they rank by).
    window_before, window_after : float
        That error of the model under test and with the effect, degrees.
    state : str
        The state of the SDP analysis that names the word.
    named_by_data : bool
        Whether the SDP analysis names that state (docs/methods.md section 8.2).
    own_before, own_after : float
        The windowed error on the runs the model was identified from, without and with the effect,
        degrees (NaN: not compared).
    carries_over : bool
        Whether it is no worse there beyond the tie band (docs/methods.md section 8.4).
    refused : str
        Why the data hold no cause for the word (empty: none found missing).

    """

    effect: str
    applicable: bool
    gain: float = 0.0
    t: float = 0.0
    significant: bool = False
    parameters: dict[str, object] = field(default_factory=dict)
    evidence: str = ''
    signature_match: bool = False
    p_value: float = 1.0
    held_out: float = 0.0
    window_before: float = 0.0
    window_after: float = 0.0
    accepted: bool = False
    state: str = ''
    named_by_data: bool = False
    own_before: float = math.nan
    own_after: float = math.nan
    carries_over: bool = True
    refused: str = ''


#: A detector's answer: the candidate, and the augmented model when there is one.
Trial = tuple[Candidate, JointModel | None]


@dataclass(frozen=True)
class LedgerStep:
    """
    One iteration of the workflow.

    Attributes
    ----------
    mae_before : float
        Validation simulation MAE before adding it, degrees.
    window_before, window_after : float
        The windowed simulation error the decision weighed, before and after, degrees.

    """

    effect: str
    parameters: dict[str, object]
    mae_before: float
    mae_after: float
    window_before: float = 0.0
    window_after: float = 0.0


@dataclass(frozen=True, eq=False)
class Signature:
    """
    The residual signature that named an effect, before and after adding it.

    Attributes
    ----------
    dt : float
        Sample period, s.
    before, after : FloatArray
        Velocity residuals (measured minus predicted increments) of the model given and of the
        augmented model, degrees per sample.
    x : FloatArray or None
        Per-sample value of the feature (``command``, ``angle``), aligned with the residuals; None
        for the event features.
    triggers : IntArray
        Residual indices of the events (``events``, ``reversals``); empty otherwise.
    signs : FloatArray
        Sign of each event (direction of the change or of the new motion); for the angle words, the
        direction of the model's motion at every sample instead.
    ends : IntArray or None
        Where each run ends in the residuals when several are joined (exclusive); None for one run.

    """

    effect: str
    feature: Feature
    label: str
    dt: SamplePeriod
    before: FloatArray
    after: FloatArray
    x: FloatArray | None
    triggers: IntArray
    signs: FloatArray
    ends: IntArray | None = None

    def part_end(self, index: int) -> int:
        """Return the end (exclusive) of the run that residual ``index`` belongs to."""
        if self.ends is None or self.ends.size == 0:
            return int(self.before.size)
        return int(self.ends[min(int(np.searchsorted(self.ends, index, side='right')),
                                 self.ends.size - 1)])

    @classmethod
    def joined(cls, parts: Sequence[Signature]) -> Signature:
        """
        Return the signatures of several runs as one, runs one after the other.

        ``parts``: signatures of one effect on successive runs (at least one).
        """
        first = parts[0]
        ends = np.cumsum([part.before.size for part in parts]).astype(np.int64)
        offsets = np.r_[0, ends[:-1]]
        xs = [part.x for part in parts]
        return cls(first.effect, first.feature, first.label, first.dt,
                   np.concatenate([part.before for part in parts]),
                   np.concatenate([part.after for part in parts]),
                   None if any(x is None for x in xs) else np.concatenate(
                       [x for x in xs if x is not None]),
                   np.concatenate([part.triggers + offset
                                   for part, offset in zip(parts, offsets)]).astype(np.int64),
                   np.concatenate([part.signs for part in parts]), ends)


@dataclass(frozen=True, eq=False)
class GapTraces:
    """
    A validation record simulated with the model given and with the augmented model.

    Attributes
    ----------
    measured, before, after : FloatArray
        Measured angle and the two simulations, degrees.

    """

    t: FloatArray
    measured: FloatArray
    before: FloatArray
    after: FloatArray


@dataclass(frozen=True, eq=False)
class StateEvidence:
    """
    The SDP estimate that named an effect: what the model misses along its state.

    Attributes
    ----------
    share : float
        Share of the squared residual the state's dependence removes (held out).
    before, after : tuple[StateDependence, ...]
        The ratio (per direction) and the residual along the state, for the model given and for the
        model with the effect.

    """

    effect: str
    state: str
    share: float
    before: tuple[StateDependence, ...]
    after: tuple[StateDependence, ...]


@dataclass(frozen=True, eq=False)
class Diagnosis:
    """
    What the workflow found.

    Attributes
    ----------
    effect : str
        The first (and largest) effect named, or ``none``.
    ledger : tuple[LedgerStep, ...]
        The effects added in turn, with the validation MAE before and after each.
    mae_before : float
        Validation MAE of the model given, degrees.
    mae_after : float
        Validation MAE of the final model, degrees.
    signature : Signature or None
        The residual signature of the first effect named, on the first estimation record; None when
        nothing was named.
    evidence : StateEvidence or None
        The SDP estimate along the state that named the first effect, before and after (None when
        nothing was named or the state was not analysed).
    validation : str
        Which records the decision and the MAE were judged on.
    shares : dict[str, float]
        The first round's share of each state analysed (docs/methods.md section 8.2).

    """

    effect: str
    model: JointModel
    ledger: tuple[LedgerStep, ...]
    candidates: tuple[Candidate, ...]
    rounds: tuple[tuple[Candidate, ...], ...]
    mae_before: float
    mae_after: float
    gap: GapTraces
    signature: Signature | None
    evidence: StateEvidence | None = None
    validation: str = ''
    shares: dict[str, float] = field(default_factory=dict)

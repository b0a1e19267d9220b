"""
The search loop of the discrepancy workflow (docs/methods.md section 8.4).

Every registered detector adds its effect to the model and fits it; a candidate
is *significant* when its residuals are smaller than the model's block by block
(block sign test, z > 3) and by a useful margin (2 %); the largest significant
improvement names the effect. It is kept only if the simulation error on the
validation records shrinks, and the search repeats on the augmented model until
nothing significant is left: ``none``.

"""

from __future__ import annotations

from typing import Callable, Sequence

from hydro_sdp.core.diagnosis.context import Context
from hydro_sdp.core.diagnosis.detectors import detector, DETECTORS
from hydro_sdp.core.diagnosis.residuals import mae, Run, runs_of
from hydro_sdp.core.diagnosis.results import (
    Candidate, Diagnosis, Gap, LedgerStep, Signature, Trial)
from hydro_sdp.core.errors import DataError, HydroSdpError
from hydro_sdp.core.identification.evaluation import simulated_record
from hydro_sdp.core.model.joint_model import JointModel
from hydro_sdp.core.model.records import Record
import numpy as np


#: Residual samples the signature figure draws at most (whole runs, the first ones).
SIGNATURE_SAMPLES = 60_000


def _signature(word: str, model: JointModel, augmented: JointModel,
               runs: Sequence[Run]) -> Signature:
    """
    Return the signature of ``word`` over the first runs, up to :data:`SIGNATURE_SAMPLES`.

    Several runs, because one may not show it: a full-stroke run moves one way only.
    """
    parts: list[Signature] = []
    samples = 0
    for run in runs:
        if parts and samples + run.record.y.size - run.start > SIGNATURE_SAMPLES:
            break
        parts.append(detector(word).signature(model, augmented, run))
        samples += parts[-1].before.size
    return Signature.joined(parts)


def _round(context: Context, progress: Callable[[str], None] | None) -> list[Trial]:
    """
    Try every detector on the model under test, ranked: significant first, by gain.

    A significant candidate whose signature the data show (motion ending at one angle
    whenever it is driven there: a stop; a speed that changes along the stroke alike in
    both directions: the linkage) goes before the others.
    """
    results: list[Trial] = []
    for each in DETECTORS:
        if progress is not None:
            progress(each.word)
        try:
            results.append(each.fit(context))
        except (HydroSdpError, np.linalg.LinAlgError, ValueError) as error:
            results.append((Candidate(each.word, False, evidence=f'could not be fitted: '
                                      f'{error}'), None))
    return sorted(results, key=lambda item: (not item[0].significant,
                                             not item[0].signature_match, -item[0].gain))


def _gap(model: JointModel, augmented: JointModel, run: Run) -> Gap:
    record = run.record
    start, before = simulated_record(model, record, run.dt, run.exogenous)
    later, after = simulated_record(augmented, record, run.dt, run.exogenous)
    start = max(start, later)
    return Gap(record.t[start:], record.y[start:], before[start:], after[start:])


def diagnose(records: Sequence[Record], model: JointModel, *,
             validation: Sequence[Record] | None = None, max_iterations: int = 4,
             max_delay: float = 0.5,
             progress: Callable[[str], None] | None = None) -> Diagnosis:
    """
    Name what the model misses, add it, and repeat until nothing significant is left.

    Parameters
    ----------
    records : sequence of Record
        Measured records of the joint (estimation data).
    model : JointModel
        The model to hold against them.
    validation : sequence of Record or None
        Held-out records for the MAE before and after (default: the estimation records).
    max_iterations : int
        Most effects added.
    max_delay : float
        Largest delay considered, s.
    progress : callable or None
        Called with the word of each detector as it starts.

    Returns
    -------
    Diagnosis
        The named effect, the ledger, the candidates, the augmented model and the
        evidence for the report (the gap on the first validation record, the
        signature of the first effect on the first estimation record).

    """
    if not records:
        raise DataError('no records to diagnose')
    runs = runs_of(records, max_delay)
    checks = runs_of(validation, max_delay) if validation else runs
    dt = runs[0].dt
    horizon = max(2, int(round(max_delay / dt)))
    before = mae(model, checks)
    current, current_mae = model, before
    ledger: list[LedgerStep] = []
    rounds: list[tuple[Candidate, ...]] = []
    for _ in range(max_iterations):
        ranked = _round(Context(current, runs, horizon), progress)
        rounds.append(tuple(candidate for candidate, _ in ranked))
        chosen = None
        for candidate, augmented in ranked:
            if not candidate.significant or augmented is None:
                break
            after = mae(augmented, checks)
            if after < current_mae:
                chosen = (candidate, augmented, after)
                break
        if chosen is None:
            break
        candidate, current, after = chosen
        ledger.append(LedgerStep(candidate.effect, candidate.parameters, current_mae, after))
        current_mae = after
    signature = _signature(ledger[0].effect, model, current, runs) if ledger else None
    return Diagnosis(effect=ledger[0].effect if ledger else 'none', model=current,
                     ledger=tuple(ledger), candidates=rounds[0] if rounds else (),
                     rounds=tuple(rounds), mae_before=before, mae_after=current_mae,
                     gap=_gap(model, current, checks[0]), signature=signature)

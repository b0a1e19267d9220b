"""The search loop of the discrepancy workflow (docs/methods.md section 8.4)."""

from __future__ import annotations

from dataclasses import replace
from typing import Callable, Sequence

from hydro_sdp.core.diagnosis.context import Context
from hydro_sdp.core.diagnosis.decision import (
    carry_over, confounded_by_records, explained_away, judge, on_common_samples, rank)
from hydro_sdp.core.diagnosis.detectors import detector, DETECTORS
from hydro_sdp.core.diagnosis.naming import name_states, Naming
from hydro_sdp.core.diagnosis.reduction import bootstrap_block
from hydro_sdp.core.diagnosis.residuals import (
    BLOCK_SECONDS, free_runs, mae, Run, runs_of, velocity_residuals)
from hydro_sdp.core.diagnosis.results import (
    Candidate, Diagnosis, GapTraces, LedgerStep, Signature, StateEvidence)
from hydro_sdp.core.errors import DataError, HydroSdpError
from hydro_sdp.core.identification.evaluation import simulated_record
from hydro_sdp.core.identification.held_out import WindowErrors
from hydro_sdp.core.identification.state_dependence import analyse
from hydro_sdp.core.model.joint_model import JointModel
from hydro_sdp.core.model.records import Record
import numpy as np


#: Residual samples the signature figure draws at most (whole runs, the first ones).
SIGNATURE_SAMPLES = 60_000


def _signature(word: str, model: JointModel, augmented: JointModel,
               runs: Sequence[Run]) -> Signature:
    """Return the signature of ``word`` over the first runs, up to :data:`SIGNATURE_SAMPLES`."""
    parts: list[Signature] = []
    samples = 0
    for run in runs:
        if parts and samples + run.record.y.size - run.start > SIGNATURE_SAMPLES:
            break
        parts.append(detector(word).signature(model, augmented, run))
        samples += parts[-1].before.size
    return Signature.joined(parts)


def hold_out(records: Sequence[Record]) -> tuple[list[Record], list[Record], str]:
    """
    Hold out whole recordings to judge the candidates on: every third, from three on.

    Returns: ``(estimation, held_out, note)``.
    """
    keys = [record.source or f'#{index}' for index, record in enumerate(records)]
    sources = list(dict.fromkeys(keys))
    if len(sources) < 3:
        return list(records), list(records), ('in-sample: fewer than three recordings and no '
                                              'validation records')
    held = {sources[i] for i in range(2, len(sources), 3)}
    estimation = [r for r, key in zip(records, keys) if key not in held]
    checks = [r for r, key in zip(records, keys) if key in held]
    return estimation, checks, (f'held out: {len(held)} of {len(sources)} recordings '
                                '(every third)')


#: The state of the words judged on the samples where the joint can move: how it moves
#: after a command change (held at a stop or stalled, it does not).
MOVING = 'since_change'


def _round(whole: Context, all_checks: Sequence[Run],
           progress: Callable[[str], None] | None,
           every: bool = True) -> list[tuple[Candidate, JointModel | None]]:
    """Fit the detectors on the estimation runs, judge each on the held-out runs, rank."""
    model = whole.model
    free = Context(model, free_runs(whole.runs, model, whole.max_delay, whole.rest),
                   whole.max_delay, whole.naming)
    free_checks = free_runs(all_checks, model, whole.max_delay, whole.rest)
    residuals = velocity_residuals(model, all_checks)
    block = bootstrap_block(residuals, max(2, int(round(BLOCK_SECONDS / all_checks[0].dt))))
    # Per side (all samples, free ones): context, held-out runs, residuals, errors.
    sides = {False: (whole, all_checks, residuals,
                     WindowErrors(all_checks), WindowErrors(whole.runs)),
             True: (free, free_checks, velocity_residuals(model, free_checks),
                    WindowErrors(free_checks), WindowErrors(free.runs))}
    judged: list[tuple[Candidate, JointModel | None]] = []
    # Judged on the estimation runs (the records' own factors): compared apart.
    on_own: list[tuple[Candidate, JointModel | None]] = []
    for each in DETECTORS:
        if progress is not None:
            progress(each.word)
        context, checks, base, errors, _ = sides[each.state == MOVING]
        again = getattr(each, 'refits', False) and context.model.effect(each.word) is not None
        if not (every or again or each.word == 'angle_limits' or
                context.naming.named(each.state)):
            judged.append((Candidate(each.word, False, evidence=f'not tried: the SDP analysis '
                                     f'finds no dependence on {each.state}'), None))
            continue
        try:
            trial = each.fit(context)
            if not every and trial[1] is not None:
                trial = (trial[0], _refit_added(context, trial[1], each.word))
        except (HydroSdpError, np.linalg.LinAlgError, ValueError) as error:
            trial = (Candidate(each.word, False, evidence=f'could not be fitted: {error}'),
                     None)
        if 'records' in trial[0].parameters:
            # Factors of the records themselves hold for no other record: judged on those;
            # the records' scales differing beyond their noise is what names the word.
            own = velocity_residuals(context.model, context.runs)
            on_own.append((replace(judge(trial, context.model, context.runs, own, block,
                                         context.naming, each.state,
                                         WindowErrors(context.runs)), named_by_data=True),
                           trial[1]))
            continue
        judged.append((judge(trial, context.model, checks, base, block, context.naming,
                             each.state, errors), trial[1]))
    judged = explained_away([(carry_over(candidate, model, augmented,
                                         sides[detector(candidate.effect).state == MOVING][4]),
                              augmented) for candidate, augmented in judged])
    # Each side compared over its own samples.
    judged = [pair for moving in (False, True) for pair in on_common_samples(
        [pair for pair in judged if (detector(pair[0].effect).state == MOVING) == moving],
        model, sides[moving][3])]
    judged = confounded_by_records(judged, on_own) + list(on_own)
    models = {id(candidate): augmented for candidate, augmented in judged}
    ranked = rank([candidate for candidate, _ in judged], whole.naming)
    return [(candidate, models[id(candidate)]) for candidate in ranked]


def _refit_added(context: Context, augmented: JointModel, word: str) -> JointModel:
    """Fit again, with the new effect, the effects added before that are fitted again."""
    for each in DETECTORS:
        if each.word == word or not getattr(each, 'refits', False) or \
                augmented.effect(each.word) is None:
            continue
        refit = each.fit(Context(augmented, context.runs, context.max_delay, context.naming))[1]
        if refit is not None and \
                context.squared_residual(refit) < context.squared_residual(augmented):
            augmented = refit
    return augmented


def _gap(model: JointModel, augmented: JointModel, run: Run) -> GapTraces:
    record = run.record
    start, before = simulated_record(model, record, run.dt, run.exogenous)
    later, after = simulated_record(augmented, record, run.dt, run.exogenous)
    start = max(start, later)
    return GapTraces(record.t[start:], record.y[start:], before[start:], after[start:])


def _evidence(effect: str, naming: Naming, records: Sequence[Record],
              augmented: JointModel) -> StateEvidence | None:
    """Return the SDP estimate along the named state, for the model and the augmented one."""
    state = detector(effect).state
    before = tuple(naming.entries(state))
    if not before:
        return None
    try:
        after = analyse(records, model=augmented, states=(state,), replicates=0)
    except (HydroSdpError, np.linalg.LinAlgError, ValueError):
        return None
    entries = tuple(e for e in after.dependence(state) if e.parameter in ('ratio', 'residual'))
    return StateEvidence(effect, state, naming.shares.get(state, 0.0), before, entries)


def diagnose(records: Sequence[Record], model: JointModel, *,
             validation: Sequence[Record] | None = None, max_iterations: int = 4,
             max_delay: float = 0.5,
             progress: Callable[[str], None] | None = None) -> Diagnosis:
    """
    Name what the model misses, add it, and repeat until no candidate is accepted.

    Parameters
    ----------
    records : sequence of Record
        Measured records of the joint (estimation data).
    model : JointModel
        The model to hold against them.
    validation : sequence of Record or None
        Held-out records the candidates are judged on and the MAE before and after is
        reported for (default: every third recording is held out, from three
        recordings on; else the estimation records themselves).
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
        signature of the first effect on the first estimation record, the SDP
        estimate along its state).

    See Also
    --------
    identify : the model diagnosed.
    calibrate : identification, diagnosis and design in one call.

    Examples
    --------
    >>> from hydro_sdp import diagnose
    >>> found = diagnose(records, model)  # doctest: +SKIP
    >>> found.effect, found.model.effects  # doctest: +SKIP

    """
    if not records:
        raise DataError('no records to diagnose')
    if validation:
        estimation, held, note = list(records), list(validation), (
            f'given: {len(validation)} validation record{"s" if len(validation) > 1 else ""}')
    else:
        estimation, held, note = hold_out(records)
    runs = runs_of(estimation, max_delay)
    checks = runs_of(held, max_delay, settle=0.0)
    dt = runs[0].dt
    horizon = max(2, int(round(max_delay / dt)))
    before = mae(model, checks)
    current, current_mae = model, before
    ledger: list[LedgerStep] = []
    rounds: list[tuple[Candidate, ...]] = []
    namings: list[Naming] = []
    first_model = model
    for iteration in range(max_iterations):
        naming = name_states(estimation, current, seed=iteration)
        namings.append(naming)
        ranked = _round(Context(current, runs, horizon, naming), checks, progress,
                        every=iteration == 0)
        rounds.append(tuple(candidate for candidate, _ in ranked))
        chosen = next(((c, m) for c, m in ranked if c.accepted and m is not None), None)
        if chosen is None:
            break
        candidate, current = chosen
        if not ledger:
            first_model = current
        after = mae(current, checks)
        ledger.append(LedgerStep(candidate.effect, candidate.parameters, current_mae, after,
                                 candidate.window_before, candidate.window_after))
        current_mae = after
    first = ledger[0].effect if ledger else 'none'
    signature = _signature(first, model, current, runs) if ledger else None
    evidence = _evidence(first, namings[0], estimation, first_model) if ledger else None
    return Diagnosis(effect=first, model=current, ledger=tuple(ledger),
                     candidates=rounds[0] if rounds else (), rounds=tuple(rounds),
                     mae_before=before, mae_after=current_mae,
                     gap=_gap(model, current, checks[0]), signature=signature,
                     evidence=evidence, validation=note,
                     shares=dict(namings[0].shares) if namings else {})

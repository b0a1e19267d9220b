"""The decision: which candidate is named, weighing the size of what it explains (methods 8.4)."""

from __future__ import annotations

from dataclasses import replace
from typing import Sequence

from hydro_sdp.core.arrays import FloatArray
from hydro_sdp.core.diagnosis.naming import Naming
from hydro_sdp.core.diagnosis.reduction import reduction_test
from hydro_sdp.core.diagnosis.residuals import MIN_GAIN, Run, velocity_residuals
from hydro_sdp.core.diagnosis.results import Candidate, Trial
from hydro_sdp.core.identification.held_out import judge as held_out_judge, WindowErrors
from hydro_sdp.core.model.joint_model import JointModel

#: The windowed simulation error on held-out data must fall by at least this share.
MARGIN = 0.1
#: A candidate removing at least this share of the held-out squared velocity residual is
#: never dismissed (when it also lowers the windowed error).
MOST = 0.5
#: No candidate raises the held-out simulation error over whole runs by more than this share.
RISE = 0.25
#: Words that hold a simpler word as a special case (different delays for the two
#: directions hold one delay for both): the richer is named before the simpler only
#: when its windowed error is lower by :data:`MARGIN` of the simpler's.
NESTED = {'direction_dependent_delay': 'time_delay'}


def judge(trial: Trial, model: JointModel, checks: Sequence[Run], base: Sequence[FloatArray],
          block: int, naming: Naming, state: str, errors: WindowErrors) -> Candidate:
    """
    Judge one candidate on the held-out runs.

    ``trial``: the candidate and its augmented model (None: nothing to judge).
    ``base``: the model's velocity residuals on them.
    ``block``: block length of the bootstrap, samples.
    ``state``: the state of the candidate's word.
    ``errors``: the simulation errors on the held-out runs (the model's made once a round).
    """
    candidate, augmented = trial
    named = naming.named(state) and _direction_agrees(candidate.effect, naming)
    if candidate.effect == 'stroke_geometry' and not named:
        # A factor shared by both directions tells the linkage from gravity, not the
        # angle from another state that moves with it (records at different loads that
        # cover different angles): without the data naming the angle it ranks by size.
        candidate = replace(candidate, signature_match=False)
    if augmented is None or not candidate.applicable:
        return replace(candidate, state=state, named_by_data=named, significant=False,
                       accepted=False)
    reduction = reduction_test(base, velocity_residuals(augmented, checks), block)
    before, after = errors.compare([model, augmented])
    held = 1.0 - after / before if before > 0.0 else 0.0
    size = held >= MARGIN and reduction.gain >= MIN_GAIN
    accepted = (reduction.significant and size) or (reduction.gain >= MOST and held > 0.0)
    whole_before, whole_after = errors.compare([model, augmented], seconds=None) \
        if accepted else (0.0, 0.0)
    drifts = whole_after > (1.0 + RISE) * whole_before
    accepted = accepted and not drifts
    evidence = candidate.evidence
    if candidate.refused:
        # Refused by its detector (its cause is not in the runs): what it would remove, said.
        accepted = False
        evidence = (f'{evidence}; it would remove {100 * held:.3g} % of the held-out error '
                    f'and {100 * reduction.gain:.3g} % of the residual')
    elif not accepted:
        # What the fit found is not a finding until the decision says so.
        if drifts:
            why = (f'it lowers the windowed error by {100 * held:.3g} % but raises the '
                   f'held-out error over whole runs from {whole_before:.3g} to '
                   f'{whole_after:.3g} deg')
        elif reduction.gain <= 0.0:
            why = (f'no better on held-out data: it adds {-100 * reduction.gain:.3g} % to '
                   'the residual')
        elif reduction.significant:
            why = (f'too small to name: it removes {100 * held:.3g} % of the held-out '
                   f'error (a name needs {100 * MARGIN:g} %) and '
                   f'{100 * reduction.gain:.3g} % of the residual')
        else:
            why = (f'not significant: it removes {100 * reduction.gain:.3g} % of the '
                   f'held-out residual, z {reduction.z:.2g}, p {reduction.p_value:.2g}')
        evidence = f'{why}; the fit would say that {evidence}' if evidence else why
    return replace(candidate, gain=reduction.gain, t=reduction.z, p_value=reduction.p_value,
                   significant=reduction.significant, held_out=held, window_before=before,
                   window_after=after, accepted=accepted, state=state, named_by_data=named,
                   evidence=evidence)


def carry_over(candidate: Candidate, model: JointModel, augmented: JointModel | None,
               own: WindowErrors) -> Candidate:
    """
    Refuse an accepted candidate that makes the runs the model came from worse.

    ``augmented``: the model with the candidate's effect.
    ``own``: the simulation errors on the runs the model was identified from.
    """
    if not candidate.accepted or augmented is None:
        return candidate
    table = own.per_record([augmented, model])
    weights = [float(len(run.record)) for run in own.runs]
    judgement = held_out_judge((candidate.effect, 'model'), table.tolist(), weights)
    after, before = judgement.pooled
    if judgement.chosen == 0:
        return replace(candidate, own_before=before, own_after=after)
    why = (f'it does not carry over: on the runs the model was identified from it raises '
           f'the windowed error from {before:.3g} to {after:.3g} deg (tie band '
           f'{judgement.bands[0]:.3g} deg)')
    return replace(candidate, own_before=before, own_after=after, carries_over=False,
                   accepted=False, evidence=f'{why}; {candidate.evidence}'
                   if candidate.evidence else why)


#: Words whose cause, where the data show it, explains the same samples as an angle factor:
#: while one of them is accepted, ``stroke_geometry`` waits for the next round.
EXPLAINS_ANGLE = ('angle_limits', 'load_dependence')


def explained_away(judged: Sequence[tuple[Candidate, JointModel | None]]
                   ) -> list[tuple[Candidate, JointModel | None]]:
    """
    Refuse ``stroke_geometry`` in a round where a stop or a load is accepted.

    ``judged``: the round's judged candidates.
    """
    causes = [c.effect for c, _ in judged if c.accepted and c.effect in EXPLAINS_ANGLE]
    if not causes:
        return list(judged)
    out = []
    for candidate, augmented in judged:
        if candidate.effect == 'stroke_geometry' and candidate.accepted:
            why = (f'{" and ".join(causes)} explain{"s" if len(causes) == 1 else ""} the same '
                   'samples: the factor is tried again once it is added')
            candidate = replace(candidate, accepted=False, refused=why,
                                evidence=f'{why}; {candidate.evidence}')
        out.append((candidate, augmented))
    return out


#: Words whose cause the runs hold apart from the joint's own speed (another joint moving).
OWN_CAUSE = ('flow_sharing',)


def confounded_by_records(judged: Sequence[tuple[Candidate, JointModel | None]],
                          on_own: Sequence[tuple[Candidate, JointModel | None]]
                          ) -> list[tuple[Candidate, JointModel | None]]:
    """
    Hold back the words that may stand in for records differing in speed for no cause seen.

    An accepted word that removes less of its held-out error than the records' own speed
    scales remove of theirs waits, unless its cause is in the runs (methods 8.4).

    ``judged``: the round's candidates judged on the held-out runs.
    ``on_own``: those judged on the records themselves (per-record factors).
    """
    differ = [c for c, _ in on_own if c.refused and c.held_out > 0.0]
    if not differ:
        return list(judged)
    lead = max(differ, key=lambda c: c.held_out)
    out = []
    for candidate, augmented in judged:
        if (candidate.accepted and candidate.effect not in OWN_CAUSE
                and candidate.held_out < lead.held_out):
            why = (f'the records differ in speed beyond their noise ({lead.effect} per record '
                   f'would remove {100 * lead.held_out:.3g} % of their error, this word '
                   f'{100 * candidate.held_out:.3g} %): fitted to all of them at once it may '
                   'stand in for that difference; record the load to tell')
            candidate = replace(candidate, accepted=False, refused=why,
                                evidence=f'{why}; {candidate.evidence}')
        out.append((candidate, augmented))
    return out


def on_common_samples(judged: Sequence[tuple[Candidate, JointModel | None]],
                      model: JointModel, errors: WindowErrors
                      ) -> list[tuple[Candidate, JointModel | None]]:
    """
    Return the judged candidates with the accepted ones' windowed errors over the same samples.

    ``judged``: candidates judged on the runs of ``errors``, with their augmented models.
    Returns: ``judged``, the accepted candidates' held-out share and windowed errors now over the
    samples they share.
    """
    accepted = {i: augmented for i, (candidate, augmented) in enumerate(judged)
                if candidate.accepted and augmented is not None}
    if len(accepted) < 2:
        return list(judged)
    before, *after = errors.compare([model, *accepted.values()])
    alike = list(judged)
    for i, error in zip(accepted, after):
        candidate, augmented = alike[i]
        held = 1.0 - error / before if before > 0.0 else 0.0
        alike[i] = (replace(candidate, held_out=held, window_before=before,
                            window_after=error), augmented)
    return alike


def _direction_agrees(word: str, naming: Naming) -> bool:
    """Along the angle, a shared factor is ``stroke_geometry`` and a mirrored one gravity."""
    if word == 'stroke_geometry':
        return naming.shared
    if word == 'angle_dependent_velocity':
        return not naming.shared
    return True


def rank(candidates: Sequence[Candidate], naming: Naming) -> list[Candidate]:
    """
    Return the candidates in the order they are tried: accepted first, by held-out gain.

    Returns: accepted candidates first, by the share of the held-out windowed error they remove;
    the others after, by size; a richer word after the simpler word it holds unless it lowers the
    windowed error by :data:`MARGIN` more.
    """
    def key(candidate: Candidate) -> tuple[bool, float, float]:
        return (not candidate.accepted, -candidate.held_out, -candidate.gain)
    ranked = sorted(candidates, key=key)
    for richer, simpler in NESTED.items():
        place = {candidate.effect: i for i, candidate in enumerate(ranked)}
        if richer not in place or simpler not in place or place[richer] > place[simpler]:
            continue
        rich, simple = ranked[place[richer]], ranked[place[simpler]]
        if rich.accepted and simple.accepted and \
                rich.window_after > (1.0 - MARGIN) * simple.window_after:
            ranked.insert(place[richer], ranked.pop(place[simpler]))
    return ranked

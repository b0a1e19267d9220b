"""The decision: accepted candidates over the samples they share, carried over, their causes."""

from dataclasses import replace
import math

from hydro_sdp.core.diagnosis.decision import (
    carry_over, explained_away, judge, on_common_samples, RISE)
from hydro_sdp.core.diagnosis.naming import Naming
from hydro_sdp.core.diagnosis.residuals import runs_of, velocity_residuals
from hydro_sdp.core.diagnosis.results import Candidate
from hydro_sdp.core.identification.held_out import WINDOW_SECONDS, WindowErrors
from hydro_sdp.core.model.effects import ValveLag
from hydro_sdp.core.model.joint_model import JointModel
import numpy as np
import pytest
from support.diagnosis_grid import hide, records_of


def test_accepted_candidates_are_compared_over_the_same_samples():
    rng = np.random.default_rng(4)
    truth, _ = hide('valve_lag', rng, 'volt')
    model = JointModel.from_mapping({**truth.mapping, 'effects': {}})
    runs = runs_of(records_of(truth, 'random', rng, seconds=20.0, count=1), 0.5)
    # A lag's candidate is compared from later than a delay's: its state forgets the
    # record's start only after a few time constants.
    lagged = model.with_effect(ValveLag(0.3))
    later = replace(model, delay=model.delay + 0.05)
    judged = [(Candidate('valve_lag', True, 0.3, 5.0, True, held_out=0.4, accepted=True),
               lagged),
              (Candidate('time_delay', True, 0.2, 4.0, True, held_out=0.5, accepted=True),
               later),
              (Candidate('backlash', True, 0.1, 1.0, False, held_out=0.7), model)]
    pairwise = WindowErrors(runs).compare([model, later])
    errors = WindowErrors(runs)
    alike = on_common_samples(judged, model, errors)
    before, lag_after, delay_after = errors.compare([model, lagged, later])
    (lag, _), (delay, _), (rejected, _) = alike
    assert lag.window_before == delay.window_before == before
    assert (lag.window_after, delay.window_after) == (lag_after, delay_after)
    assert lag.held_out == pytest.approx(1.0 - lag_after / before)
    assert delay.held_out == pytest.approx(1.0 - delay_after / before)
    # The delay's own comparison started earlier, over samples the lag's leaves out.
    assert pairwise[0] != pytest.approx(before)
    # Candidates not accepted keep what their own judgement found.
    assert rejected is judged[2][0]


class _Errors(WindowErrors):
    """Held-out errors as given: windows mended, whole runs worse."""

    def __init__(self, runs, windows, whole):
        super().__init__(runs)
        self.windows, self.whole = windows, whole

    def compare(self, models, seconds=WINDOW_SECONDS):
        return list(self.windows if seconds is not None else self.whole)


def test_a_word_that_mends_windows_but_drifts_over_whole_runs_is_refused():
    # The right delay, so that the residual test passes: what decides is the rise.
    rng = np.random.default_rng(6)
    truth, nominal = hide('time_delay', rng, 'volt')
    model, right = JointModel.from_mapping(nominal), JointModel.from_mapping(truth.mapping)
    runs = runs_of(records_of(truth, 'random', rng, seconds=20.0, count=1), 0.5)
    base = velocity_residuals(model, runs)
    naming = Naming(None, {'since_change': 1.0})
    trial = (Candidate('time_delay', True, evidence='fitted'), right)
    kept = judge(trial, model, runs, base, 50, naming, 'since_change',
                 _Errors(runs, (1.0, 0.5), (1.0, 1.0 + 0.9 * RISE)))
    assert kept.accepted and kept.held_out == pytest.approx(0.5)
    refused = judge(trial, model, runs, base, 50, naming, 'since_change',
                    _Errors(runs, (1.0, 0.5), (1.0, 1.0 + 1.1 * RISE)))
    assert not refused.accepted and refused.significant
    assert refused.evidence.startswith('it lowers the windowed error by 50 % but raises the '
                                       'held-out error over whole runs from 1 to 1.27 deg')


def test_a_candidate_worse_on_the_runs_the_model_came_from_is_refused():
    rng = np.random.default_rng(5)
    truth, _ = hide('none', rng, 'volt')
    model = JointModel.from_mapping(truth.mapping)
    own = WindowErrors(runs_of(records_of(truth, 'random', rng, seconds=20.0, count=2), 0.5))
    accepted = Candidate('valve_lag', True, 0.3, 5.0, True, held_out=0.4, accepted=True,
                         evidence='fitted')
    # A lag the joint does not have makes its own runs worse: it does not carry over.
    lagged = carry_over(accepted, model, model.with_effect(ValveLag(0.3)), own)
    assert not lagged.accepted and not lagged.carries_over
    assert lagged.own_after > lagged.own_before > 0.0
    assert lagged.evidence.startswith('it does not carry over') and 'fitted' in lagged.evidence
    # The same model again is within its tie band: kept, with both figures.
    same = carry_over(accepted, model, replace(model), own)
    assert same.accepted and same.carries_over and same.own_after == same.own_before
    # A candidate not accepted is not compared.
    assert math.isnan(carry_over(replace(accepted, accepted=False), model, model, own).own_after)


def test_a_stop_or_a_load_accepted_puts_the_angle_factor_off_a_round():
    def candidate(word, accepted=True):
        return (Candidate(word, True, 0.3, 5.0, True, held_out=0.5, accepted=accepted,
                          evidence='fit'), None)
    judged = explained_away([candidate('stroke_geometry'), candidate('angle_limits')])
    geometry = judged[0][0]
    assert not geometry.accepted and 'angle_limits explains the same samples' in geometry.refused
    assert judged[1][0].accepted
    # Neither accepted: the factor stands.
    alone = explained_away([candidate('stroke_geometry'), candidate('load_dependence', False)])
    assert alone[0][0].accepted and not alone[0][0].refused

"""The data name the state: the SDP analysis of what a model misses, on the generator's joints."""

from hydro_sdp.core.diagnosis.decision import rank
from hydro_sdp.core.diagnosis.naming import agreement_of, MIN_SHARE, name_states, Naming
from hydro_sdp.core.diagnosis.results import Candidate
from hydro_sdp.core.identification.state_dependence import StateDependence
import numpy as np
import pytest
from support.diagnosis_grid import make_case


def named(word: str, kind: str = 'random', units: str = 'volt', seed: int = 0) -> Naming:
    """Analyse what the nominal model of a grid case misses, on two 30 s records."""
    case = make_case(word, kind, units, seed, seconds=30.0)
    return name_states(case.estimation, case.model)


@pytest.mark.parametrize('word, state', [
    ('valve_lag', 'since_change'), ('backlash', 'reversals'), ('flow_sharing', 'others_speed'),
    ('load_dependence', 'load'), ('asymmetry', 'command'), ('dead_zone', 'command')])
def test_the_state_of_the_missing_word_names_it(word, state):
    naming = named(word)
    assert naming.analysis is not None and naming.named(state), naming.shares
    assert naming.shares[state] >= MIN_SHARE


def test_a_correct_model_leaves_no_state_named():
    naming = named('none')
    assert naming.order() == [], naming.shares


def test_along_the_angle_a_shared_factor_and_a_mirrored_one_are_told_apart():
    shared = named('stroke_geometry', 'stroke', 'signed_percent')
    assert shared.named('angle') and shared.shared and shared.agreement > 0.5
    mirrored = named('angle_dependent_velocity', 'stroke', 'signed_percent')
    assert mirrored.named('angle') and not mirrored.shared


def test_agreement_of_two_curves_over_their_common_range():
    values = np.linspace(-30.0, 40.0, 50)

    def entry(direction, estimate, where=values):
        return StateDependence('angle', 'ratio', direction, 0.1, 1.0, 0.0, True, where,
                               estimate, np.full(where.size, 0.01), 1.0, 100)
    up = entry('positive', 1.0 + 0.2 * np.sin(values / 10.0))
    assert agreement_of(up, entry('negative', 1.0 + 0.1 * np.sin(values / 10.0))) == \
        pytest.approx(1.0)
    assert agreement_of(up, entry('negative', 1.0 - 0.1 * np.sin(values / 10.0))) == \
        pytest.approx(-1.0)
    # Curves seen over ranges that barely meet are not compared.
    apart = np.linspace(35.0, 90.0, 50)
    assert agreement_of(up, entry('negative', 1.0 + apart / 100.0, apart)) is None


def test_accepted_candidates_rank_by_held_out_gain_whatever_their_word():
    def candidate(word, held, accepted=True, named=True, signature=False):
        return Candidate(word, True, 0.3, 5.0, True, held_out=held, accepted=accepted,
                         named_by_data=named, signature_match=signature)
    candidates = [candidate('valve_lag', 0.9, named=False), candidate('dead_zone', 0.4),
                  candidate('asymmetry', 0.6), candidate('backlash', 0.95, accepted=False),
                  candidate('stroke_geometry', 0.2, signature=True)]
    # No fixed order of words, no signature first: the held-out gain ranks.
    order = [c.effect for c in rank(candidates, Naming(None))]
    assert order == ['valve_lag', 'asymmetry', 'dead_zone', 'stroke_geometry', 'backlash']

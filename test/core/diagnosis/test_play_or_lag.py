"""
Play told from a valve lag on the independent generator, both ways.

Play between actuator and sensor loses motion after reversals only; a lag of the speed
leaves a tail after every change. The joint of :mod:`support.confusions` (no package
simulation), its model identified from steps of the joint without either, diagnosed on
40 s of random levels with each hidden at a size small beside its neighbours (0.3 deg of
play, 0.06 s of lag behind a 0.12 s delay) and judged on another 40 s: each is named for
what it is with the gap halved. ``test/support/confusions.py`` runs more seeds and sizes
(docs/methods.md section 8.7).

"""

from hydro_sdp.core.diagnosis import diagnose
import pytest
from support.confusions import case, HIDDEN

pytestmark = [pytest.mark.slow(5)]


@pytest.mark.parametrize('hidden', ['small_play', 'small_lag'])
def test_play_and_lag_are_not_taken_for_each_other(hidden):
    model, estimation, validation = case(hidden, 5)
    result = diagnose(estimation, model, validation=validation, max_iterations=1)
    assert result.effect == HIDDEN[hidden], [(c.effect, c.held_out) for c in result.candidates]
    first = result.ledger[0]
    assert first.mae_after <= 0.5 * first.mae_before
    # The other word fits something too, and removes less.
    other = next(c for c in result.candidates if c.effect ==
                 ('valve_lag' if hidden == 'small_play' else 'backlash'))
    assert other.held_out < result.candidates[0].held_out

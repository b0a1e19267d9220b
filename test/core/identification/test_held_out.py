"""The one held-out mechanism: folds that never extrapolate, and the rule every choice follows."""

import math

from hydro_sdp.core.identification.held_out import deal, judge, MARGIN, Unit
import numpy as np
import pytest


def test_the_least_error_wins_when_it_is_clearly_least():
    judgement = judge(['simple', 'rich'], [(1.0, 0.5), (1.2, 0.6), (0.9, 0.45)], [10, 10, 10])
    assert judgement.chosen == 1 and judgement.best == 1
    assert judgement.pooled == pytest.approx((31 / 30, 31 / 60))
    assert judgement.lower_on(1) == 3 and judgement.gain(1) == pytest.approx(0.5)
    assert 'the least held-out error' in judgement.verdict()


def test_a_simpler_candidate_within_the_margin_wins_the_tie():
    # 3 % better everywhere: inside the 5 % floor, whatever the folds say.
    judgement = judge(['simple', 'rich'], [(1.0, 0.97), (2.0, 1.94)], [1, 1])
    assert judgement.best == 1 and judgement.chosen == 0
    assert 'the simpler wins a tie' in judgement.verdict()
    assert judgement.bands[0] == pytest.approx(MARGIN * 1.5)


def test_a_gain_that_comes_from_one_fold_only_is_a_tie():
    # Pooled 25 % better, but worse on one fold of two: within one standard error.
    judgement = judge(['without', 'effect'], [(1.0, 0.3), (1.0, 1.2)], [1, 1])
    assert judgement.gain(1) == pytest.approx(0.25)
    assert judgement.chosen == 0
    assert judgement.bands[0] == pytest.approx(np.std([0.7, -0.2], ddof=1) / math.sqrt(2))


def test_no_decision_turns_on_the_last_bits_of_a_sum():
    # Two candidates equal but for rounding: the simpler, whichever rounds lower.
    for eps in (1e-15, -1e-15):
        assert judge(['a', 'b'], [(1.0, 1.0 + eps), (2.0, 2.0 + eps)], [5, 5]).chosen == 0


def test_unscored_candidates_are_left_out_and_none_scored_chooses_nothing():
    judgement = judge(['a', 'b', 'c'], [(math.nan, 2.0, 1.0), (math.nan, 2.0, 1.0)], [1, 1])
    assert judgement.chosen == 2 and math.isnan(judgement.pooled[0])
    nothing = judge(['a'], [(math.nan,)], [1])
    assert nothing.chosen == -1 and nothing.verdict() == 'nothing could be scored'


def test_folds_never_ask_for_a_level_outside_the_training_levels():
    levels = [-100, -80, -60, -40, 40, 60, 80, 100]
    units = [Unit(i, float(level), int(np.sign(level))) for i, level in enumerate(levels)]
    parts = deal(units)
    assert len(parts) == 2
    held = sorted(levels[i] for _, test in parts for i in test)
    assert held == [-80, -60, 60, 80]           # the outermost always train
    for train, test in parts:
        for i in test:
            side = [levels[j] for j in train if np.sign(levels[j]) == np.sign(levels[i])]
            assert min(side, key=abs) != levels[i] and abs(levels[i]) < max(map(abs, side))


def test_repeated_levels_and_groups_are_spread_and_kept_together():
    units = [Unit('a', 1.0, 1), Unit('b', 1.0, 1), Unit('r1'), Unit('r1'), Unit('r2'),
             Unit('r3')]
    parts = deal(units, 3)
    tests = [sorted(test) for _, test in parts]
    assert tests == [[0, 2, 3], [1, 4], [5]]
    # Every third recording held out: the one split the diagnosis uses.
    records = [Unit(name) for name in 'abcdefg']
    assert deal(records, 3)[2][1] == [2, 5]

"""The bookkeeping of held-out errors over folds, shared by experiments and routine operation."""

import math
from types import SimpleNamespace

from hydro_sdp.core.errors import DataError
from hydro_sdp.core.identification.family_choice import FoldErrors
import pytest


class HeldOut:
    """Stands for a fold's held-out data: the error of a map is its rate at command 1."""

    samples = 100

    def simulation_mae(self, rate):
        return float(rate(1.0))


def gain(value):
    """Stand for a map whose rate is ``value`` everywhere."""
    return SimpleNamespace(rate=lambda command: value)


def test_a_family_that_fails_on_one_fold_is_dropped_the_others_averaged():
    tally = FoldErrors(['sdp', 'pwl', 'poly'])
    gains = iter([1.0, 3.0, 2.0, 6.0])

    def first(kind):
        if kind == 'pwl':
            raise DataError('too few levels for the knots')
        return gain(next(gains))

    def second(kind):
        assert kind != 'pwl'       # not fitted again once it failed
        return gain(next(gains))
    tally.add_fold(HeldOut(), first)
    tally.add_fold(HeldOut(), second)
    sdp, pwl, poly = tally.scores()
    assert (sdp.kind, sdp.mae, sdp.note) == ('sdp', pytest.approx(1.5), '')
    assert (pwl.kind, pwl.note) == ('pwl', 'too few levels for the knots')
    assert math.isnan(pwl.mae)
    assert (poly.kind, poly.mae) == ('poly', pytest.approx(4.5))
    judgement = tally.judgement()
    assert judgement.names == ('sdp', 'poly', 'pwl')
    assert judgement.chosen == 0 and tally.chosen() == 'sdp'
    assert math.isnan(judgement.pooled[2]) and math.isnan(judgement.bands[2])


def test_a_failure_of_the_shared_fit_leaves_no_family_scored():
    tally = FoldErrors(['sdp', 'pwl'])
    tally.add_fold(HeldOut(), lambda kind: gain(2.0))
    tally.fail(DataError('no motion in the training part'))
    assert [(s.kind, s.note) for s in tally.scores()] == [
        ('sdp', 'no motion in the training part'), ('pwl', 'no motion in the training part')]
    assert all(math.isnan(s.mae) for s in tally.scores())
    with pytest.raises(DataError, match='no map family could be fitted: sdp: no motion'):
        tally.chosen()


def test_no_fold_gives_no_score():
    scores = FoldErrors(['sdp']).scores()
    assert len(scores) == 1 and math.isnan(scores[0].mae) and scores[0].note == ''

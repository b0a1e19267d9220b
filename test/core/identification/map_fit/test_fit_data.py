"""FitData's bulk residuals equal the regret-regression recursion run one sample at a time."""

import math

from hydro_sdp.core.identification.experiment import Experiment
from hydro_sdp.core.identification.map_fit import FitData
import numpy as np
import pytest


def _rate(v):
    return np.where(np.abs(v) < 1.0, 0.0, 10.0 * np.tanh(v))


def _loop(experiment, delay, dt, lag, beta, gain):
    """Return Z_k of docs/methods.md section 2, one sample at a time."""
    p = math.exp(-dt / lag) if lag > 0.0 else 0.0
    v, y, start = experiment.v, experiment.y, experiment.start
    state, lagged, out = float(y[start]), None, []
    for n, k in enumerate(range(start + 1, y.size)):
        raw = dt * float(_rate(np.array([v[max(k - delay, 0)]]))[0])
        lagged = raw if lagged is None else p * lagged + (1.0 - p) * raw
        predicted = state + lagged * (1.0 if gain is None else gain[n])
        residual = y[k] - predicted
        state = predicted + beta * residual
        out.append(residual)
    return out


@pytest.mark.parametrize('lag', [0.0, 0.05])
@pytest.mark.parametrize('beta', [0.0, 0.4])
@pytest.mark.parametrize('with_gains', [False, True])
def test_residuals_follow_the_recursion(rng, lag, beta, with_gains):
    # Lengths that share padded blocks unevenly, starts after the first sample, one
    # experiment with a single sample to predict.
    experiments = []
    for length, start in [(40, 0), (57, 3), (64, 0), (100, 7), (130, 2), (9, 7), (300, 0)]:
        v = rng.choice([-3.0, -1.5, 0.0, 2.0, 4.0], length)
        y = np.cumsum(rng.normal(0.0, 0.05, length)) + 0.01 * np.cumsum(_rate(v))
        experiments.append(Experiment(v, y, start, 'step', float(v[-1]), 0.0))
    gains = [rng.uniform(0.5, 1.5, e.y.size - e.start - 1) for e in experiments] \
        if with_gains else None
    data = FitData(experiments, 4, 0.01, lag, gains)
    expected = np.concatenate([
        _loop(e, 4, 0.01, lag, beta, None if gains is None else gains[i])
        for i, e in enumerate(experiments)])
    # Residuals come bucket by bucket (experiments of similar length): put them back in order.
    got = data.residuals(_rate, beta)
    assert got.size == expected.size == data.samples == sum(e.y.size - e.start - 1
                                                            for e in experiments)
    order = np.concatenate([np.flatnonzero(_member_order(data) == i)
                            for i in range(len(experiments))])
    np.testing.assert_allclose(got[order], expected, rtol=0.0, atol=1e-9)


def _member_order(data):
    """Return, per residual, the index of the experiment it belongs to."""
    owners = []
    for members, _, _, mask, _ in data.buckets:
        owners.append(np.repeat(members, mask.sum(axis=1)))
    return np.concatenate(owners)

"""SRIV/RIV estimation of discrete transfer functions against known systems."""

import warnings

from hydro_sdp.core.errors import DataError
from hydro_sdp.core.identification.riv import NotConvergedWarning, sriv
from hydro_sdp.core.identification.structure_search import structure_search
import numpy as np
import pytest
from scipy.signal import lfilter

A = [1.0, -1.5, 0.7]
B = [1.0, 0.5]
DELAY = 2


def _second_order(rng, noise=0.5, samples=1000):
    u = np.repeat(rng.choice([-1.0, 1.0], samples // 10), 10)
    x = lfilter(np.r_[np.zeros(DELAY), B], A, u)
    return x + rng.normal(0.0, noise, x.size), u


def test_sriv_recovers_a_second_order_system_with_delay(rng):
    y, u = _second_order(rng)
    estimate = sriv(y, u, n=2, m=1, delay=DELAY)
    assert estimate.converged and estimate.iterations <= 5
    np.testing.assert_allclose(estimate.a, A, atol=0.02)
    np.testing.assert_allclose(estimate.b, B, atol=0.08)
    assert estimate.structure == (2, 2, 2)
    assert estimate.rt2 > 0.99 and estimate.fit > 90.0
    assert np.isfinite(estimate.yic) and estimate.yic < -10.0
    assert estimate.sigma2 == pytest.approx(0.25, rel=0.15)


def test_standard_errors_match_the_monte_carlo_spread(rng):
    estimates, errors = [], []
    for _ in range(50):
        y, u = _second_order(rng)
        estimate = sriv(y, u, n=2, m=1, delay=DELAY)
        estimates.append(estimate.parameters)
        errors.append(estimate.standard_errors)
    spread = np.std(estimates, axis=0, ddof=1)
    predicted = np.mean(errors, axis=0)
    np.testing.assert_allclose(predicted, spread, rtol=0.3)
    np.testing.assert_allclose(np.mean(estimates, axis=0), [-1.5, 0.7, 1.0, 0.5], atol=0.02)


def test_known_integrator_is_least_squares_on_the_integrated_input(rng):
    outputs, inputs = [], []
    for level in rng.uniform(-3, 3, 20):
        u = np.r_[np.zeros(5), np.full(100, level)]
        y = lfilter([0.0, 0.0, 0.0, 0.4], [1.0, -1.0], u) + rng.normal(0.0, 0.05, u.size)
        outputs.append(y)
        inputs.append(u)
    estimate = sriv(outputs, inputs, n=0, m=0, delay=3, known_factor=[1.0, -1.0])
    np.testing.assert_allclose(estimate.a, [1.0, -1.0])
    # docs/methods.md section 1.4 (a): b = sum y U / sum U^2 over the pooled experiments.
    integrated = [np.r_[np.zeros(3), np.cumsum(u)[:-3]] for u in inputs]
    closed = sum(np.dot(y[3:], U[3:]) for y, U in zip(outputs, integrated)) / \
        sum(np.dot(U[3:], U[3:]) for U in integrated)
    assert estimate.b[0] == pytest.approx(closed, rel=1e-9)
    assert estimate.b[0] == pytest.approx(0.4, abs=1e-3)
    assert estimate.standard_errors[0] < 1e-3


def test_experiments_are_not_filtered_across_their_boundaries(rng):
    pieces = [_second_order(rng, noise=0.05, samples=300) for _ in range(4)]
    pooled = sriv([p[0] for p in pieces], [p[1] for p in pieces], 2, 1, DELAY)
    np.testing.assert_allclose(pooled.a, A, atol=0.01)
    # Gluing the experiments end to end pretends they are one: the jumps at the seams
    # are not explained by the model, and the fit is worse.
    glued = sriv(np.concatenate([p[0] for p in pieces]), np.concatenate([p[1] for p in pieces]),
                 2, 1, DELAY)
    assert pooled.rt2 > glued.rt2


def test_riv_with_ar_noise(rng):
    u = np.repeat(rng.choice([-1.0, 1.0], 300), 10)
    x = lfilter(np.r_[np.zeros(DELAY), B], A, u)
    coloured = lfilter([1.0], [1.0, -0.8], rng.normal(0.0, 0.3, x.size))
    estimate = sriv(x + coloured, u, 2, 1, DELAY, noise_order=1)
    np.testing.assert_allclose(estimate.a, A, atol=0.02)
    assert estimate.noise_ar[1] == pytest.approx(-0.8, abs=0.05)


def test_structure_search_finds_the_true_structure(rng):
    y, u = _second_order(rng, noise=0.3)
    rows = structure_search(y, u, n_range=[1, 2, 3], m_range=[0, 1, 2], delay_range=[1, 2, 3])
    found = {(row.n, row.m, row.delay): row for row in rows}
    # The true [2 2 2] is among the two best (a third pole can mimic its zero equally well);
    # over-parameterising raises YIC sharply and under-parameterising loses R_T^2
    # (docs/methods.md section 1.8).
    assert (2, 1, 2) in [(row.n, row.m, row.delay) for row in rows[:2]]
    assert found[(3, 2, 2)].yic > found[(2, 1, 2)].yic + 2.0
    assert found[(1, 0, 2)].rt2 < found[(2, 1, 2)].rt2 - 0.05
    assert rows[0].converged and rows[0].stable
    ranked = structure_search(y, u, [1, 2], [1], [1, 2, 3], criterion='rt2')
    assert ranked[0].rt2 >= ranked[-1].rt2


def test_bad_data(rng):
    with pytest.raises(DataError, match='too few samples'):
        sriv(np.zeros(4), np.zeros(4), 2, 1, 1)
    with pytest.raises(DataError, match='not finite'):
        sriv(np.r_[np.zeros(20), np.nan], np.zeros(21), 1, 0, 1)
    with pytest.raises(DataError, match='equal length'):
        sriv([np.zeros(20)], [np.zeros(21)], 1, 0, 1)
    y, u = _second_order(rng)
    with warnings.catch_warnings():
        warnings.simplefilter('error', NotConvergedWarning)
        with pytest.raises(NotConvergedWarning):
            sriv(y, u, 3, 2, DELAY, max_iterations=1, tol=1e-15)

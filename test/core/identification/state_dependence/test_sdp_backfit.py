"""Back-fitting recovers known state dependences, CAPTAIN's example, and weighs them honestly."""

import math

from hydro_sdp.core.identification.state_dependence.backfit import backfit, Term
import numpy as np
import pytest
from scipy.signal import lfilter


def inside_bands(term, truth):
    """Share of the groups where the truth lies within the estimate's +-2 standard errors."""
    return float(np.mean(np.abs(term.estimate - truth(term.values)) <= 2.0 * term.standard_error))


def sine(chi):
    return 1.0 + 0.5 * np.sin(2.5 * chi)


def logistic(chi):
    return 0.2 + 1.0 / (1.0 + np.exp(-4.0 * chi))


@pytest.mark.parametrize('kind', ['rw', 'irw'])
def test_parameters_that_are_known_functions_of_states_are_recovered_inside_their_bands(kind):
    # Neither a sine nor a logistic is a map family of the package.
    rng = np.random.default_rng(11)
    n = 3000
    chi1, chi2 = rng.uniform(-1.5, 1.5, n), rng.normal(0.0, 0.8, n)
    x1, x2 = rng.normal(0.0, 1.0, n), rng.uniform(0.5, 2.0, n)
    z = sine(chi1) * x1 + logistic(chi2) * x2 + rng.normal(0.0, 0.3, n)
    fit = backfit(z, [Term('sine', x1, chi1, kind), Term('logistic', x2, chi2, kind)],
                  replicates=99)
    assert fit.converged
    sine_term, logistic_term = fit.terms
    assert inside_bands(sine_term, sine) > 0.9
    assert inside_bands(logistic_term, logistic) > 0.9
    # The bands are not so wide that anything would lie inside them.
    assert np.median(sine_term.standard_error) < 0.1
    assert np.max(np.abs(sine_term.estimate - sine(sine_term.values))) < 0.25
    assert sine_term.p_value <= 0.01 and logistic_term.p_value <= 0.01
    assert sine_term.share > 0.15 and logistic_term.share > 0.05


def test_captain_sdpdemo_example():
    # CAPTAIN's sdpdemo: y = a{x1} u1 + b{x2} u2 + c{x3} u3 + noise, 1500 samples, states and
    # inputs white noise, a = 0.5 x1 + 3 (RW), b = x2^2 + 1 and c = sin(pi x3 / 2) + 2 (IRW),
    # noise standard deviation 3 (a noise-to-signal ratio of about 50 % by variance).
    rng = np.random.default_rng(0)
    n = 1500
    x1, x2, x3, u1, u2, u3 = rng.normal(size=(6, n))
    truths = (lambda s: 0.5 * s + 3.0, lambda s: s ** 2 + 1.0,
              lambda s: np.sin(s * np.pi / 2.0) + 2.0)
    y = truths[0](x1) * u1 + truths[1](x2) * u2 + truths[2](x3) * u3 + 3.0 * rng.normal(size=n)
    fit = backfit(y, [Term('a', u1, x1, 'rw'), Term('b', u2, x2, 'irw'),
                      Term('c', u3, x3, 'irw')], replicates=99)
    for term, truth in zip(fit.terms, truths):
        # Within the central 95 % of the state, where the demo's own plots are read.
        central = np.abs(term.values) < 2.0
        error = np.abs(term.estimate - truth(term.values))[central]
        assert np.mean(error <= 2.0 * term.standard_error[central]) > 0.85, term.term.name
        assert term.p_value <= 0.01
    # b = x2^2 + 1 is the strongest dependence, as the demo's figures show.
    assert max(fit.terms, key=lambda t: t.share).term.name == 'b'


def null_and_effect(seed, amplitude, phi, n=3000):
    """Back-fit a gain along a slowly drifting state, with AR(1) noise of unit variance."""
    rng = np.random.default_rng(seed)
    state = np.cumsum(rng.normal(0.0, 1.0, n))
    state = (state - state.min()) / np.ptp(state)
    x = rng.choice([0.0, 0.5, 1.0, 1.5], n)
    noise = lfilter([1.0], [1.0, -phi], rng.normal(0.0, 1.0, n)) * math.sqrt(1.0 - phi ** 2)
    z = (1.0 + amplitude * np.sin(2.0 * np.pi * state)) * x + noise
    return backfit(z, [Term('gain', x, state)], replicates=199, seed=seed).terms[0]


def test_autocorrelated_errors_along_a_slow_state_are_not_a_dependence():
    # The state drifts as a random walk in time and the errors are AR(1) with 0.95: they look
    # smooth along the state, a trap for any test that treats them as independent.
    p_values = [null_and_effect(seed, 0.0, 0.95).p_value for seed in range(10)]
    assert sum(p < 0.01 for p in p_values) <= 1
    # A real dependence as large as the noise is found through the same errors, and a
    # half as large one through less correlated errors.
    assert all(null_and_effect(seed, 1.0, 0.95).significant for seed in range(3))
    assert all(null_and_effect(seed, 0.5, 0.5).significant for seed in range(3))


def test_a_state_that_labels_the_samples_explains_nothing_held_out():
    # Each of 30 runs drifts over its own stretch of the state, with its own gain: in-sample
    # the state fits each run, on held-out runs it predicts nothing.
    rng = np.random.default_rng(4)
    runs = 30
    stretch = rng.permutation(runs)
    state = np.concatenate([np.linspace(s, s + 0.9, 100) for s in stretch])
    gain = np.repeat(rng.normal(1.0, 0.3, runs), 100)
    x = np.ones(state.size)
    z = gain * x + rng.normal(0.0, 0.1, state.size)
    term = backfit(z, [Term('gain', x, state)], replicates=0).terms[0]
    assert term.fit_share > 0.5
    assert term.share < 0.05

"""The block bootstrap of a candidate's reduction: it weighs magnitude and autocorrelation."""

from hydro_sdp.core.diagnosis.reduction import reduction_test
import numpy as np
import pytest
from scipy.signal import lfilter


def test_a_large_effect_in_two_blocks_of_sixty_is_significant():
    # Sixty one-second blocks of white noise (0.03 deg per sample); in two of them the
    # model moves the joint 0.3 deg per sample where it stands still at a stop: the
    # candidate with the stop leaves the noise there. A sign test of blocks counts 2
    # better against 0 worse (z = 1.4); the reduction is a hundred times its noise.
    rng = np.random.default_rng(3)
    noise = rng.normal(0.0, 0.03, 6000)
    base = noise.copy()
    base[3000:3200] -= 0.3
    result = reduction_test([base], [noise], 100)
    assert result.gain > 0.7 and result.significant
    assert result.p_value == pytest.approx(1.0 / 1000.0)
    # The standard score is the cluster-robust t of the regression of the model's
    # residual on the candidate's change: sum(eps d) / sqrt(sum_b (sum eps' d)^2).
    change = base - noise
    blocks = np.add.reduceat(noise * change, np.arange(0, 6000, 100))
    assert result.z == pytest.approx(np.dot(base, change) / np.sqrt(np.dot(blocks, blocks)))
    assert result.z > 50.0


def test_a_change_unrelated_to_the_residual_is_not_significant():
    # The model is right (its residual is noise); a candidate changes the prediction by a
    # smooth signal the noise does not follow: it adds its square, the test says so.
    rng = np.random.default_rng(4)
    significant = 0
    for trial in range(20):
        noise = rng.normal(0.0, 0.03, 4000)
        change = 0.01 * np.sin(np.arange(4000) / 150.0 + trial)
        result = reduction_test([noise], [noise - change], 100, seed=trial)
        significant += result.significant
        assert result.gain < 0.0
    assert significant == 0


def test_autocorrelated_noise_along_a_fitted_change_is_not_significant_too_often():
    # Residuals with a slow AR(1) component (coefficient 0.99 per sample) and a candidate
    # that removes its least-squares projection on a slow sine (one parameter fitted to the
    # noise): the blocks keep the correlation, so at most a few of 40 come out significant
    # at p <= 0.01 (a test that took the samples as independent would find most).
    rng = np.random.default_rng(5)
    significant = 0
    for trial in range(40):
        slow = lfilter([1.0], [1.0, -0.99], rng.normal(0.0, 0.01, 6000))
        residual = slow + rng.normal(0.0, 0.03, 6000)
        shape = np.sin(np.arange(6000) / 400.0 + trial)
        fitted = shape * np.dot(shape, residual) / np.dot(shape, shape)
        significant += reduction_test([residual], [residual - fitted], 100,
                                      seed=trial).significant
    assert significant <= 4


def test_several_runs_and_a_candidate_that_leaves_nothing():
    base = [np.r_[np.zeros(150), np.full(50, 0.2)], np.zeros(120)]
    perfect = [np.zeros(200), np.zeros(120)]
    result = reduction_test(base, perfect, 100)
    assert result.gain == pytest.approx(1.0) and result.significant and result.z == np.inf
    # Nothing to remove: no gain, no verdict.
    empty = reduction_test([np.zeros(50)], [np.zeros(50)], 10)
    assert (empty.gain, empty.z, empty.p_value) == (0.0, 0.0, 1.0)

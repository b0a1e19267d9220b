"""The fixed-interval smoother three ways: recursive Kalman filter, banded, dense; ties; limits."""

import math

from hydro_sdp.core.errors import DataError
from hydro_sdp.core.identification.state_dependence.banded import (
    fit_banded, fit_flat, penalty_bands, selected_inverse_diagonal)
from hydro_sdp.core.identification.state_dependence.kalman import kalman_smooth
from hydro_sdp.core.identification.state_dependence.ordering import order_by_state
from hydro_sdp.core.identification.state_dependence.random_walk import group_stats, STENCILS
import numpy as np
import pytest


def grouped_data(kind, seed, groups=80):
    """Observations of a smooth parameter, 1-4 per group (ties), regressor sometimes zero."""
    rng = np.random.default_rng(seed)
    counts = rng.integers(1, 5, groups)
    group = np.repeat(np.arange(groups), counts)
    x = rng.normal(0.0, 1.0, group.size)
    x[rng.random(group.size) < 0.1] = 0.0
    p = np.sin(group / 9.0) + (0.02 * group if kind == 'irw' else 0.0)
    return group, x, x * p + rng.normal(0.0, 0.3, group.size)


def dense_solution(group, x, z, kind, nvr, prior):
    """Minimise |z - X p|^2 + |D p|^2 / nvr (+ the initial state's prior) by a dense solve."""
    groups = int(group[-1]) + 1
    d = len(STENCILS[kind]) - 1
    D = np.diff(np.eye(groups), n=d, axis=0)
    X = np.zeros((z.size, groups))
    X[np.arange(z.size), group] = x
    A = X.T @ X + D.T @ D / nvr
    if prior is not None:
        start = np.zeros((d, groups))
        start[0, 0] = 1.0
        if d == 2:          # (p_0, s_0 = p_1 - p_0) ~ N(0, prior I)
            start[1, :2] = (-1.0, 1.0)
        A = A + start.T @ start / prior
    return np.linalg.solve(A, X.T @ z), np.diag(np.linalg.inv(A))


@pytest.mark.parametrize('kind', ['rw', 'irw'])
@pytest.mark.parametrize('nvr', [1e-4, 0.05, 2.0])
def test_kalman_smoother_banded_and_dense_solutions_agree(kind, nvr):
    group, x, z = grouped_data(kind, seed=3)
    prior = 1e5         # CAPTAIN's default P0
    kalman = kalman_smooth(z, x, group, kind, nvr, prior=prior)
    banded = fit_banded(group_stats(z, x, group, int(group[-1]) + 1), kind, nvr, prior=prior)
    dense, variance = dense_solution(group, x, z, kind, nvr, prior)
    np.testing.assert_allclose(kalman.smoothed, dense, rtol=0.0, atol=1e-8)
    np.testing.assert_allclose(banded.estimate, dense, rtol=0.0, atol=1e-8)
    # The smoothed variances: the FIS covariance, diag(A^-1) from the banded factor.
    np.testing.assert_allclose(kalman.variance, variance, rtol=1e-8, atol=1e-12)
    np.testing.assert_allclose(banded.variance(), variance, rtol=1e-8, atol=1e-12)
    np.testing.assert_allclose(kalman.standard_error, banded.standard_error(), rtol=1e-7)
    # The prediction-error decomposition of the filter is the banded likelihood, exactly.
    assert kalman.sigma2 == pytest.approx(banded.sigma2, rel=1e-9)
    assert kalman.neg2_log_likelihood == pytest.approx(banded.neg2_log_likelihood, abs=1e-7)


@pytest.mark.parametrize('kind', ['rw', 'irw'])
def test_the_diffuse_start_is_the_limit_of_a_wide_prior(kind):
    group, x, z = grouped_data(kind, seed=5)
    stats = group_stats(z, x, group, int(group[-1]) + 1)
    diffuse = fit_banded(stats, kind, 0.01)
    dense, _ = dense_solution(group, x, z, kind, 0.01, None)
    np.testing.assert_allclose(diffuse.estimate, dense, rtol=0.0, atol=1e-8)
    wide = kalman_smooth(z, x, group, kind, 0.01, prior=1e9)
    np.testing.assert_allclose(wide.smoothed, diffuse.estimate, atol=1e-5)

    def diffuse_neg2(result):
        # The filter's diffuse likelihood: without the d innovations of the diffuse start.
        keep = result.innovation_variance < 1e6
        assert np.count_nonzero(~keep) == len(STENCILS[kind]) - 1
        f, eps = result.innovation_variance[keep], result.innovations[keep]
        sigma2 = np.mean(eps ** 2 / f)
        return np.sum(np.log(f)) + f.size * (math.log(2.0 * math.pi * sigma2) + 1.0)
    # Up to a constant of the start, the banded likelihood is the filter's.
    other = kalman_smooth(z, x, group, kind, 0.1, prior=1e9)
    assert diffuse_neg2(other) - diffuse_neg2(wide) == pytest.approx(
        fit_banded(stats, kind, 0.1).neg2_log_likelihood - diffuse.neg2_log_likelihood,
        abs=1e-4)


@pytest.mark.parametrize('kind', ['rw', 'irw'])
def test_zero_nvr_is_the_limit_of_the_walk(kind):
    group, x, z = grouped_data(kind, seed=7)
    stats = group_stats(z, x, group, int(group[-1]) + 1)
    flat = fit_flat(stats, kind)
    # A constant (rw) or a line in rank (irw), by weighted least squares.
    basis = np.ones((stats.groups, 1)) if kind == 'rw' else np.column_stack(
        [np.ones(stats.groups), np.arange(stats.groups)])
    rows = basis[group] * x[:, None]
    np.testing.assert_allclose(flat.estimate, basis @ np.linalg.lstsq(rows, z, rcond=None)[0],
                               atol=1e-10)
    # The walk's likelihood tends to the flat one: the two are comparable.
    for nvr in (1e-11, 1e-12):
        assert fit_banded(stats, kind, nvr).neg2_log_likelihood == pytest.approx(
            flat.neg2_log_likelihood, abs=2e-3)
    assert fit_banded(stats, kind, 1e-3).neg2_log_likelihood < flat.neg2_log_likelihood


def test_selected_inversion_matches_the_dense_inverse():
    rng = np.random.default_rng(1)
    for kind in ('rw', 'irw'):
        bands = penalty_bands(300, kind) / 0.37
        bands[0] += rng.uniform(0.0, 3.0, 300)
        from scipy.linalg import cholesky_banded
        factor = cholesky_banded(bands, lower=True)
        dense = np.diag(bands[0])
        for offset in range(1, bands.shape[0]):
            dense += np.diag(bands[offset, :-offset], -offset) + np.diag(bands[offset, :-offset],
                                                                         offset)
        np.testing.assert_allclose(selected_inverse_diagonal(factor),
                                   np.diag(np.linalg.inv(dense)), rtol=1e-10)


def test_ties_share_one_value_and_pooling_never_splits_them():
    state = np.array([3.0, 1.0, 2.0, 1.0, 3.0, 5.0, 2.0, 0.5])
    x = np.array([1.0, 2.0, 0.0, 1.0, 1.0, 1.0, 2.0, 1.0])
    ordering = order_by_state(state, x)
    # The sample whose regressor is zero says nothing: left out of the ordering.
    assert ordering.samples.tolist() == [0, 1, 3, 4, 5, 6, 7]
    np.testing.assert_array_equal(ordering.values, [0.5, 1.0, 2.0, 3.0, 5.0])
    assert ordering.group.tolist() == [3, 1, 1, 3, 4, 2, 0]
    many = np.repeat(np.arange(1000.0), 3)
    many[:600] = 7.0            # one large tie
    pooled = order_by_state(many, np.ones(many.size), max_groups=50)
    assert pooled.pooled and pooled.groups <= 50
    assert np.unique(pooled.group[many[pooled.samples] == 7.0]).size == 1
    for g in range(pooled.groups):
        members = many[pooled.samples][pooled.group == g]
        assert pooled.values[g] == pytest.approx(np.mean(members))
    assert np.all(np.diff(pooled.values) > 0.0)


def test_the_smoother_refuses_what_it_cannot_fit():
    with pytest.raises(DataError, match='regressor is zero'):
        order_by_state(np.arange(5.0), np.zeros(5))
    with pytest.raises(DataError, match='NaN'):
        order_by_state(np.array([1.0, math.nan]), np.ones(2))
    stats = group_stats(np.ones(4), np.ones(4), np.arange(4), 4)
    with pytest.raises(DataError, match='nvr'):
        fit_banded(stats, 'rw', -1.0)
    with pytest.raises(DataError, match='distinct state values'):
        fit_banded(group_stats(np.ones(4), np.ones(4), np.array([0, 0, 1, 1]), 2), 'irw', 1.0)

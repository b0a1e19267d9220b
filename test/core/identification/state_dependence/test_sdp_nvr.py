"""The NVR by maximum likelihood recovers a known NVR within its uncertainty."""

import math

from hydro_sdp.core.identification.state_dependence.nvr import estimate_nvr
from hydro_sdp.core.identification.state_dependence.random_walk import group_stats
import numpy as np
import pytest

GROUPS = 1500


def walk_data(kind, nvr, seed, sigma=0.5):
    """Observe a parameter that is a random walk (or an integrated one) of known NVR."""
    rng = np.random.default_rng(seed)
    steps = rng.normal(0.0, math.sqrt(nvr) * sigma, GROUPS)
    p = np.cumsum(steps) if kind == 'rw' else np.cumsum(np.cumsum(steps))
    x = rng.normal(1.0, 0.5, GROUPS)
    z = x * p + rng.normal(0.0, sigma, GROUPS)
    return group_stats(z, x, np.arange(GROUPS), GROUPS)


@pytest.mark.parametrize(('kind', 'nvr'), [('rw', 1e-2), ('rw', 1e-4), ('irw', 1e-6)])
def test_a_known_nvr_is_recovered_within_its_uncertainty(kind, nvr):
    errors = []
    for seed in range(8):
        found = estimate_nvr(walk_data(kind, nvr, seed), kind)
        assert found.nvr > 0.0 and math.isfinite(found.log_se)
        errors.append((math.log(found.nvr) - math.log(nvr)) / found.log_se)
        low, high = found.interval(3.0)
        assert low < nvr < high
    # The standard error is honest: the errors in ln nvr are about standard normal.
    assert abs(np.mean(errors)) < 1.0
    assert 0.4 < np.std(errors) < 1.6


def test_a_constant_parameter_gets_zero_nvr_most_of_the_time():
    zeros = 0
    small = 0
    for seed in range(10):
        rng = np.random.default_rng(100 + seed)
        x = rng.normal(1.0, 0.5, GROUPS)
        z = 0.7 * x + rng.normal(0.0, 0.5, GROUPS)
        found = estimate_nvr(group_stats(z, x, np.arange(GROUPS), GROUPS), 'rw')
        zeros += found.nvr == 0.0
        # Where the likelihood prefers a walk, barely: over all the groups it wanders by less
        # than the noise of one observation.
        small += found.nvr * GROUPS < 1.0
        assert found.neg2_log_likelihood <= found.neg2_log_likelihood_flat
    assert zeros >= 7 and small == 10

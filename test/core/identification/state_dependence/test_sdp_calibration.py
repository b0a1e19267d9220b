"""The dependence test is calibrated: nulls come out significant at about their level."""

import math

from hydro_sdp.core.identification.state_dependence import analyse
from hydro_sdp.core.identification.state_dependence.ordering import order_by_state
from hydro_sdp.core.identification.state_dependence.significance import dependence_test
import numpy as np
import pytest
from support.sdp_null_cases import null_case, null_pairs

pytestmark = [pytest.mark.slow(10)]


def held_levels(seed: int, gain, per_run: float, n: int = 4000):
    """
    Return runs of one held command, the speed ``gain(command)`` times each run's own factor.

    The observations, the regressor, the command and the run of every sample.
    """
    rng = np.random.default_rng(seed)
    lengths = []
    while sum(lengths) < n:
        lengths.append(int(rng.integers(50, 300)))
    levels = rng.uniform(1.0, 9.0, len(lengths))
    run = np.repeat(np.arange(len(lengths)), lengths)[:n]
    command = levels[run]
    x = 0.05 * command
    factor = 1.0 + per_run * rng.normal(size=len(lengths))[run]
    return x * gain(command) * factor + rng.normal(0.0, 0.02, n), x, command, run


def p_value(z, x, command, run, seed):
    """Test the gain of ``z = x g(command)`` against its constant, whole runs flipped."""
    ordering = order_by_state(command, x)
    e = z - x * (x @ z) / (x @ x)
    return dependence_test(e, x, command, ordering, 'rw', seed=seed, runs=run).p_value


def test_each_run_with_its_own_speed_is_not_a_dependence_on_the_command():
    # Each held command is one run and one group: a factor of the run's own (5 %) is as
    # rough along the command as a dependence could be; blocks that split the runs made
    # nearly every such record significant (methods.md section 14.5).
    # (Measured on 60 records: 10 % at p <= 0.05, 5 % at p <= 0.01; the bound is loose.)
    p = [p_value(*held_levels(seed, lambda c: 1.0, 0.05), seed) for seed in range(10)]
    assert sum(value <= 0.01 for value in p) <= 2 and sum(value <= 0.05 for value in p) <= 3
    # A smooth dependence of the same size is found through the same runs' factors.
    smooth = [p_value(*held_levels(seed, lambda c: 1.0 + 0.03 * (c - 5.0), 0.05), seed)
              for seed in range(3)]
    assert all(value <= 0.01 for value in smooth)


def test_joints_with_nothing_left_to_find_give_few_significant_pairs():
    # The true joint's model on full strokes pushed into the stops, and the SDP-ARX model of
    # a joint without lag on random levels (bench/bench_sdp_calibration.py runs the table).
    pairs = []
    for target, program in (('ratio', 'stroke'), ('arx', 'random')):
        case = null_case(target, program, 1, seconds=25.0)
        pairs += null_pairs(analyse(case.records, model=case.model), target)
    assert len(pairs) >= 20
    assert sum(p <= 0.05 for *_, p in pairs) <= math.ceil(0.1 * len(pairs))
    assert sum(p <= 0.01 for *_, p in pairs) <= 1

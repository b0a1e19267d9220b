"""
Benchmark the SDP analysis: the banded smoother against a dense solve, and a one-hour record.

Run with ``make bench`` or ``python bench/bench_sdp.py``. Prints, from one run:

* the fixed-interval smoother of a random walk on a short record (2000 groups), as the
  banded solution of :mod:`.banded` (estimates, standard
  errors and likelihood) against a dense solve of the same quadratic problem (the normal
  equations and their inverse): the ratio, and that both agree;
* the banded smoother alone over 360 000 distinct state values (no pooling);
* ``analyse`` of a one-hour 100 Hz record (360 000 samples) along one state, the delayed
  command and the angle, each against the 10 s target.

BLAS runs on one thread, as the command line runs it (:data:`hydro_sdp.cli.main.BLAS_THREADS`).

"""

import os

os.environ.setdefault('OPENBLAS_NUM_THREADS', '1')

import time  # noqa: E402
from typing import Callable  # noqa: E402

from hydro_sdp.core.identification.state_dependence import analyse  # noqa: E402
from hydro_sdp.core.identification.state_dependence.banded import (  # noqa: E402
    fit_banded, penalty_bands)
from hydro_sdp.core.identification.state_dependence.random_walk import group_stats  # noqa: E402
from hydro_sdp.core.synthetic.joint_experiments import experiment_record  # noqa: E402
from hydro_sdp.io.model_files import default_model_path, load_model  # noqa: E402
import numpy as np  # noqa: E402

TARGET = 10.0


def best_of(runs: int, work: Callable[[], object]) -> float:
    """Return the shortest wall time of ``runs`` calls, s."""
    times = []
    for _ in range(runs):
        start = time.perf_counter()
        work()
        times.append(time.perf_counter() - start)
    return min(times)


def dense(weight: np.ndarray, moment: np.ndarray, nvr: float) -> tuple[np.ndarray, np.ndarray]:
    """Solve the same normal equations densely; return the estimate and diag of the inverse."""
    bands = penalty_bands(weight.size, 'rw') / nvr
    A = np.diag(bands[0] + weight) + np.diag(bands[1, :-1], -1) + np.diag(bands[1, :-1], 1)
    return np.linalg.solve(A, moment), np.diag(np.linalg.inv(A))


def short_record() -> None:
    rng = np.random.default_rng(0)
    groups = 2000
    group = np.repeat(np.arange(groups), 2)
    x = rng.normal(1.0, 0.5, group.size)
    z = x * np.sin(group / 200.0) + rng.normal(0.0, 0.3, group.size)
    stats = group_stats(z, x, group, groups)

    def banded() -> tuple[np.ndarray, np.ndarray]:
        fit = fit_banded(stats, 'rw', 1e-3)
        return fit.estimate, fit.variance()
    estimate, variance = banded()
    # The dense solve from the data's own sums (the banded one's are about a reference).
    moment = np.bincount(group, weights=x * z, minlength=groups)
    reference, reference_variance = dense(stats.weight, moment, 1e-3)
    agree = max(float(np.max(np.abs(estimate - reference))),
                float(np.max(np.abs(variance - reference_variance))))
    fast = best_of(5, banded)
    slow = best_of(3, lambda: dense(stats.weight, moment, 1e-3))
    print(f'smoother on {groups} groups: banded {1e3 * fast:.2f} ms, dense {1e3 * slow:.1f} ms: '
          f'{slow / fast:.0f}x faster; largest difference {agree:.1e}')
    many = 360_000
    group = np.arange(many)
    x = rng.normal(1.0, 0.5, many)
    stats = group_stats(x * np.sin(group / 2e4) + rng.normal(0.0, 0.3, many), x, group, many)
    once = best_of(3, lambda: fit_banded(stats, 'rw', 1e-6).variance())
    print(f'smoother on {many} groups (no pooling), estimate and standard errors: {once:.2f} s')


def one_hour() -> None:
    model = load_model(default_model_path())
    start = time.perf_counter()
    record = experiment_record(model, 'random', duration=3600.0, seed=1)
    print(f'one-hour record: {len(record)} samples, simulated in '
          f'{time.perf_counter() - start:.1f} s')
    for state in ('command', 'angle'):
        start = time.perf_counter()
        result = analyse([record], states=[state])
        seconds = time.perf_counter() - start
        first = result.states[0]
        verdict = 'met' if seconds < TARGET else 'MISSED'
        left = sum(getattr(result, 'left_out', {}).values())
        print(f'analyse along {state}: {seconds:.1f} s (target < {TARGET:.0f} s: {verdict}); '
              f'a1 {result.a1.mean if result.a1 else float("nan"):.5f}, '
              f'{first.state} {first.direction} share {100 * first.share:.1f} %, '
              f'{left} increments held at a stop or stalled left out')


if __name__ == '__main__':
    short_record()
    one_hour()

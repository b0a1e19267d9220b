"""Sample budgets of ``identify``: thinning that keeps both directions."""

from hydro_sdp.core.identification.experiment import Experiment, thin_evenly
import numpy as np


def _step(level: float, samples: int = 100) -> Experiment:
    return Experiment(np.full(samples + 1, level), np.zeros(samples + 1), 0, 'step', level, 0.0)


def test_thinning_keeps_both_directions_of_alternating_steps() -> None:
    # Steps alternate up and down: every other one would keep one direction only.
    steps = [_step(level) for level in (1.0, -1.0, 2.0, -2.0, 3.0, -3.0, 4.0, -4.0)]
    kept = thin_evenly(steps, 400, 0.0)
    assert [e.level for e in kept] == [1.0, -1.0, 3.0, -3.0]


def test_thinning_within_budget_keeps_everything_and_splits_runs_apart() -> None:
    steps = [_step(1.0), _step(-1.0)]
    assert thin_evenly(steps, 200, 0.0) == steps
    runs = [Experiment(np.zeros(101), np.zeros(101), 0, 'run', float('nan'), float(k))
            for k in range(6)]
    kept = thin_evenly(runs + [_step(0.7)], 300, 0.5)
    # Stride 3: runs 0 and 3, and the one step above rest.
    assert [e.t0 for e in kept] == [0.0, 3.0, 0.0]
    assert kept[-1].level == 0.7

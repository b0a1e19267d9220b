"""Simulated open-loop experiments: the step and random-level programs, recorded with noise."""

from __future__ import annotations

from hydro_sdp.core.model.joint_model import JointModel
from hydro_sdp.core.model.records import Record
from hydro_sdp.core.model.simulation import simulate
from hydro_sdp.core.model.timing import SamplePeriod
from hydro_sdp.core.synthetic.programs import random_program, start_angle, step_program
import numpy as np


def experiment_record(model: JointModel, program: str, *, dt: float = 0.01, seed: int = 0,
                      duration: float | None = None, noise: float = 0.03,
                      y0: float | None = None) -> Record:
    """
    Simulate one open-loop program on ``model`` with measurement noise.

    ``dt``: sample period, s.
    ``duration``: length in s; default 40 steps, or 60 s of random levels.
    ``noise``: standard deviation of the measurement noise, degrees.
    ``y0``: starting angle; default: the middle of the end stops.
    """
    dt = SamplePeriod(dt)
    start = start_angle(model) if y0 is None else y0
    if program == 'steps':
        steps = 40 if duration is None else max(2, int(duration // 3.0))
        v = step_program(model, dt, steps=steps, y0=start)
    else:
        v = random_program(model, dt, 60.0 if duration is None else duration, seed=seed,
                           y0=start)
    y = simulate(model, v, dt, start)
    rng = np.random.default_rng([seed, 1])
    measured = y + rng.normal(0.0, noise, y.size) if noise > 0.0 else y
    # Time starts one period in, so that v_0 has a (non-negative) time to be sent at.
    t = np.arange(1, v.size + 1, dtype=np.float64) * dt
    return Record(t, v, np.asarray(measured, dtype=np.float64), joint=model.joint)

"""
Simulations restarted from the measured angle: windows whose error does not drift.

A whole record's simulation integrates every error of the model over the record;
restarted at the measured angle every few seconds it shows what a model gets right
over a few seconds (docs/methods.md section 8.4). The model's delays and lag run on
through the record; only the angle (and the play) start afresh.

"""

from __future__ import annotations

from typing import Sequence

from hydro_sdp.core.arrays import FloatArray
from hydro_sdp.core.model.effects import Backlash
from hydro_sdp.core.model.exogenous_signals import Exogenous
from hydro_sdp.core.model.joint_model import JointModel
from hydro_sdp.core.model.simulation import integrate_speed, speed_profile
import numpy as np


def simulate_windows(model: JointModel, v: FloatArray, y: FloatArray, dt: float,
                     starts: Sequence[int], *, v_before: float = 0.0,
                     exogenous: Exogenous | None = None) -> FloatArray:
    """
    Simulate the joint afresh from the measured angle at each of ``starts``.

    Each window runs from one start to the next (the last to the end of the
    record); the model's delays and lag run on through the whole record, only the
    angle is set back to the measured one at every start (and the play to the side
    the model's last motion took it up on). The error over such windows does not
    drift as a whole record's does.

    Parameters
    ----------
    model, v, dt, v_before, exogenous
        As in :func:`speed_profile`.
    y : FloatArray
        Measured angles, degrees.
    starts : sequence of int
        First sample of each window, increasing.

    Returns
    -------
    FloatArray
        Simulated angle from the first start on; NaN before it.

    """
    speed = speed_profile(model, v, dt, v_before=v_before, exogenous=exogenous)
    out = np.full(speed.size, np.nan)
    bounds = [int(s) for s in starts] + [speed.size]
    play = model.effect(Backlash.name)
    half = 0.5 * play.play if isinstance(play, Backlash) else 0.0
    # The model's last direction of motion at each sample: moving up leaves the sensor
    # the play's half behind the actuator.
    direction = np.sign(speed[np.maximum.accumulate(np.where(speed != 0.0,
                                                             np.arange(speed.size), 0))])
    for first, end in zip(bounds[:-1], bounds[1:]):
        if end > first:
            out[first:end] = integrate_speed(model, speed[first:end], dt, float(y[first]),
                                             -half * float(direction[first]))
    return out

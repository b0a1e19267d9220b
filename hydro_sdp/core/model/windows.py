"""Simulations restarted from the measured angle every few seconds: no drift (methods 8.4)."""

from __future__ import annotations

from typing import Sequence

from hydro_sdp.core.arrays import FloatArray
from hydro_sdp.core.model.effects import Backlash
from hydro_sdp.core.model.exogenous_signals import Exogenous
from hydro_sdp.core.model.joint_model import JointModel
from hydro_sdp.core.model.simulation import integrate_speed, speed_profile
from hydro_sdp.core.model.timing import SamplePeriod
import numpy as np


def simulate_windows(model: JointModel, v: FloatArray, y: FloatArray, dt: SamplePeriod,
                     starts: Sequence[int], *, v_before: float = 0.0,
                     exogenous: Exogenous | None = None) -> FloatArray:
    """
    Simulate afresh from the measured angle at each of ``starts``; delays and lag run on.

    ``y``: measured angles, degrees.
    ``starts``: first sample of each window, increasing.
    Returns: simulated angle from the first start on; NaN before it.
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

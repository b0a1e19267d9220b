"""An angle factor is never fitted to a stall: the joint held by a load it cannot lift."""

from dataclasses import replace

from hydro_sdp.core.diagnosis.context import Context
from hydro_sdp.core.diagnosis.detectors import stroke_shape
from hydro_sdp.core.diagnosis.residuals import runs_of
from hydro_sdp.core.identification.identify import identify
import numpy as np
from support.confusions import _steps, FREE
from support.joint_generator import Machine, record


def test_the_stroke_samples_leave_a_stall_out(monkeypatch):
    # The joint stops dead for 2 s mid-stroke while a load it cannot lift is on.
    stalling = replace(FREE, load_factor=lambda load, direction: 0.0 if load > 0.5 else 1.0)
    steps = record(Machine((FREE,)), _steps(FREE)[:, None], angles0=[0.0], seed=1)
    model = identify([steps], kind='sdp').model
    v = np.concatenate([np.zeros(100), np.full(500, 2.0), np.zeros(100), np.full(500, -2.0),
                        np.zeros(100)])
    load = np.zeros(v.size)
    load[250:450] = 1.0
    # Up from -60 deg, held near -30 for 2 s, on to 0 and back: no stop is met.
    run = record(Machine((stalling,)), v[:, None], angles0=[-60.0], load=load, seed=2)
    context = Context(model, runs_of([run], 0.5), 50)
    kept = stroke_shape.stroke_samples(context).angles.size
    monkeypatch.setattr(stroke_shape, 'stalled', lambda *a: np.zeros(len(a[1]), dtype=bool))
    unguarded = stroke_shape.stroke_samples(context)
    held = np.abs(unguarded.target) < 0.2 * np.abs(unguarded.drive)
    # Without the guard the held samples (about 1.7 s of the 2 s, the rest within a delay
    # and a window of its ends) enter the fit; with it they are out.
    assert np.count_nonzero(held) > 120
    assert unguarded.angles.size - kept >= 0.9 * np.count_nonzero(held)

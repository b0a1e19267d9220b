"""The samples where the joint can move: held at a stop, ringing on it and stalled are out."""

from hydro_sdp.core.diagnosis.residuals import free_runs, runs_of, velocity_residuals
from hydro_sdp.core.model.joint_model import JointModel
from hydro_sdp.core.model.records import Record
from hydro_sdp.core.model.static_maps import LinearMap
import numpy as np

DT = 0.01
DELAY = 0.1


def stroke():
    """Drive up into a stop at 20 deg (ringing on it), hold, then back down off it."""
    t = np.arange(0.0, 6.5, DT)
    v = np.where(t < 1.0, 0.0, np.where(t < 5.0, 1.0, -1.0))
    rng = np.random.default_rng(0)
    y = np.zeros(t.size)
    for k in range(1, t.size):
        y[k] = min(y[k - 1] + DT * 10.0 * v[max(k - int(DELAY / DT), 0)], 20.0)
    arrival = int(np.argmax(y >= 20.0))
    # The link bounces on the stop's compliance for a few tenths of a second.
    since = t[arrival:] - t[arrival]
    y[arrival:] -= np.minimum(0.3 * np.exp(-since / 0.1) * np.abs(np.sin(2 * np.pi * 8 * since)),
                              y[arrival:])
    return Record(t, v, y + 0.005 * rng.standard_normal(t.size), 'boom'), arrival


def test_held_at_a_stop_and_ringing_there_is_left_out_and_motion_kept():
    record, arrival = stroke()
    model = JointModel('boom', LinearMap(10.0), DELAY, (0.0, 20.0))
    run = runs_of([record], 0.5)[0]
    free = free_runs([run], model, int(DELAY / DT), 0.0)[0].free
    # Residual i is the increment ending at sample start + 1 + i.
    at = np.arange(run.start + 1, len(record))
    reverse = int(round(5.0 / DT))
    assert free[(at > 150) & (at < arrival - 5)].all()
    assert not free[(at > arrival + 2) & (at < reverse)].any()
    # From the command away from the stop on, whether and when the joint leaves is motion:
    # the dead time's evidence.
    assert free[at > reverse].all()
    residual = velocity_residuals(model, [free_runs([run], model, 10, 0.0)[0]])[0]
    assert np.all(residual[~free] == 0.0) and np.any(residual[free] != 0.0)

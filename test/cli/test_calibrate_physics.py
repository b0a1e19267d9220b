"""
hydro-sdp calibrate on the physics plant's arm: the controller it writes settles on that plant.

The loop runs the written controller file against :class:`PlantSimulator` (spool
overlap, dead time 0.25 s, spool lag, load-sensing pump, linkage), not against
the identified model. Band: every set-point step inside the stroke settles into
+-1 deg within 10 s, overshoots less than 10 %, stays in the band to the end of
its 15 s hold, and ends without a limit cycle in the sense of the calibration's
own check (:mod:`hydro_sdp.core.control.loop_check`): over the last 5 s fewer than
``CYCLE_REVERSALS`` valve reversals and the arm within 0.5 deg. (What remains is
an occasional single correction of about 0.3 deg at the IDZ edge: the dead-zone
of a spool valve with overlap is never known exactly.)

"""

from contextlib import redirect_stdout
import io
import json

from hydro_sdp.bags import write_bag
from hydro_sdp.cli.main import main
from hydro_sdp.core.control.loop_check import CYCLE_REVERSALS
from hydro_sdp.core.control.loop_simulation import valve_reversals
from hydro_sdp.core.synthetic.physics import PlantSimulator
from hydro_sdp.core.synthetic.physics.linkage import Geometry
from hydro_sdp.core.synthetic.physics.runs import full_stroke_runs, random_levels, step_and_return
from hydro_sdp.io.controller_files import load_controller
from hydro_sdp.io.documents import shipped_config
from hydro_sdp.io.model_files import load_model
from hydro_sdp.io.plant_files import load_machine
import numpy as np
import pytest

DT = 0.01
#: Set-points, degrees: steps of 20 to 30 deg across the arm's stroke (-45..40 deg).
LEVELS = (-20.0, 10.0, 30.0, 0.0, -30.0, -10.0)
HOLD = 15.0
BAND = 1.0
SETTLE = 10.0


@pytest.fixture(scope='module')
def arm():
    return load_machine(shipped_config('physics_arm.yaml'))


@pytest.fixture(scope='module')
def calibrated(arm, tmp_path_factory):
    """Calibrate from full-stroke runs, steps and a random run; validate on another."""
    folder = tmp_path_factory.mktemp('physics')
    records = list(full_stroke_runs(arm, DT, (40, 50, 60, 70, 80, 90, 100), seed=11))
    records.append(step_and_return(arm, DT, [40, -40, 50, -50, 60, -60, 80, -80, 100, -100],
                                   hold=1.0))
    records.append(random_levels(arm, DT, 60.0, seed=3))
    bags = [str(write_bag(folder / f'run_{i}', [record])) for i, record in enumerate(records)]
    validation = str(write_bag(folder / 'validation', [random_levels(arm, DT, 60.0, seed=4)]))
    out = folder / 'arm'
    stdout = io.StringIO()
    with redirect_stdout(stdout):
        code = main(['calibrate'] + bags + ['--validation', validation, '--input-limits',
                                            '-100', '100', '--out', str(out), '--json'])
    assert code == 0
    return out, json.loads(stdout.getvalue())


def physics_loop(arm, controller_file, levels, hold):
    """
    Run a controller file against the physics plant over set-point steps.

    Returns the set-points, angles and valve commands at every plant sample.
    """
    spec = load_controller(controller_file)
    controller = spec.controller()
    every = int(round(spec.control_period / DT))
    sim = PlantSimulator(arm, DT, angles0=[levels[0]], command_before=[0.0], seed=1)
    setpoint = np.repeat(np.asarray(levels, dtype=float), int(round(hold / DT)))
    y, v = np.empty(setpoint.size), np.empty(setpoint.size)
    command = controller.last_v
    for j in range(setpoint.size):
        y[j] = sim.angles[0]
        if j % every == 0:
            command = controller.step(float(setpoint[j]), y[j])[1]
        v[j] = command
        sim.step([command])
    return setpoint, y, v


@pytest.mark.slow
def test_the_calibrated_controller_settles_on_the_physics_plant(arm, calibrated):
    out, payload = calibrated
    low, high = Geometry(arm.joints[0]).angle_limits
    assert low < min(LEVELS) and max(LEVELS) < high
    model = load_model(out / 'model.yaml')
    # The creeping power law is inverted from where the arm moves, not from its dead-zone.
    spec = load_controller(out / 'controller.yaml')
    assert spec.settings().idz.dead_zone[1] > 33.0 and spec.settings().idz.dead_zone[0] < -33.0
    assert model.dead_zone is None or model.dead_zone[1] < spec.settings().idz.dead_zone[1]
    assert payload['closed_loop']['passed']
    setpoint, y, v = physics_loop(arm, out / 'controller.yaml', LEVELS, HOLD)
    n = int(round(HOLD / DT))
    rest = spec.settings().idz.rest
    for i in range(1, len(LEVELS)):
        hold = slice(i * n, (i + 1) * n)
        error = y[hold] - LEVELS[i]
        outside = np.nonzero(np.abs(error) > BAND)[0]
        settling = (outside[-1] + 1) * DT if outside.size else 0.0
        size = LEVELS[i] - LEVELS[i - 1]
        overshoot = max(0.0, float(np.max(np.sign(size) * error))) / abs(size)
        assert settling < SETTLE, f'step {i} to {LEVELS[i]} deg settles in {settling} s'
        assert overshoot < 0.10, f'step {i} overshoots by {100 * overshoot:.1f} %'
        assert np.all(np.abs(error[outside[-1] + 1 if outside.size else 0:]) <= BAND)
        # No limit cycle over the last 5 s: the valve hunts at most once, the arm holds.
        tail = slice((i + 1) * n - 500, (i + 1) * n)
        assert valve_reversals(v[tail], rest) < CYCLE_REVERSALS, f'step {i} hunts'
        assert np.ptp(y[tail]) < 0.5

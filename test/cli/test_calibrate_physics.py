"""
hydro-sdp calibrate on the physics plant's arms: the controller files it writes settle the plant.

The loops run the written controller file against :class:`PlantSimulator` (spool
overlap of 37.5 %, a convex opening that saturates, dead time, spool lag,
load-sensing pump, linkage), not against the identified model, in the loop of
:mod:`support.independent_loop`, which reads the file itself and uses none of
hydro_sdp's controller classes. Band: every set-point step of 20-30 deg settles
into +-0.5 deg within 8 s, overshoots at most 10 % and ends its hold without a
limit cycle (over the last 2 s fewer than ``CYCLE_REVERSALS`` valve reversals and
the arm within 0.5 deg), the closed-loop check's own criteria.

Two arms and two programs: ``physics_arm.yaml`` (signed percent, 0.25 s dead
time, 0.1 s lag) from full-stroke runs, steps and random levels through the
command line; ``physics_arm_pwm.yaml`` (a PWM resting at 50 %, 0.28 s dead time,
0.15 s lag) identified on full strokes at 40/60/80/100 % and validated on
50/70/90 %, through the calibration's pipeline.

"""

from contextlib import redirect_stdout
import io
import json

from hydro_sdp.bags import write_bag
from hydro_sdp.cli.main import main
from hydro_sdp.core.calibration import calibrate, CalibrationSettings
from hydro_sdp.core.control.idz_table import TableInverseDeadZone
from hydro_sdp.core.control.loop_check import CYCLE_REVERSALS
from hydro_sdp.core.synthetic.physics.linkage import Geometry
from hydro_sdp.core.synthetic.physics.runs import full_stroke_runs, random_levels, step_and_return
from hydro_sdp.io.controller_files import load_controller, save_controller
from hydro_sdp.io.documents import shipped_config
from hydro_sdp.io.model_files import load_model
from hydro_sdp.io.plant_files import load_machine
import pytest
from support.independent_loop import FileController, judge, run_loop
from support.real_valve_joints import ESTIMATION, PhysicsJoint, VALIDATION

pytestmark = [pytest.mark.usefixtures('figures_not_drawn')]

DT = 0.01
#: Set-points, degrees: steps of 20 to 30 deg across the arm's stroke (-45..40 deg).
LEVELS = (-20.0, 10.0, 30.0, 0.0, -30.0, -10.0)
HOLD = 12.0
SETTLE = 8.0
#: Length of the random-level runs, s.
RANDOM = 30.0


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
    # Random levels, 30 s a run: the calibrated loop keeps its margins (slowest step 4.8 s).
    records.append(random_levels(arm, DT, RANDOM, seed=3))
    bags = [str(write_bag(folder / f'run_{i}', [record])) for i, record in enumerate(records)]
    validation = str(write_bag(folder / 'validation', [random_levels(arm, DT, RANDOM, seed=4)]))
    out = folder / 'arm'
    stdout = io.StringIO()
    with redirect_stdout(stdout):
        code = main(['calibrate'] + bags + ['--validation', validation, '--input-limits',
                                            '-100', '100', '--out', str(out), '--json'])
    assert code == 0
    return out, json.loads(stdout.getvalue())


def assert_settles(machine, controller_file, levels):
    """Run the file on the plant over ``levels``: the criteria of the module docstring."""
    controller = FileController.read(controller_file)
    low, high = Geometry(machine.joints[0]).angle_limits
    assert low < min(levels) and max(levels) < high
    run = run_loop(controller, PhysicsJoint(machine, levels[0]), DT, levels, HOLD)
    for r in judge(run, rest=controller.rest):
        assert r.settling < SETTLE, f'the {r.size:+.0f} deg step settles in {r.settling} s'
        assert r.overshoot <= 10.0, f'the {r.size:+.0f} deg step overshoots {r.overshoot:.1f} %'
        assert r.reversals < CYCLE_REVERSALS and r.wander <= 0.5, \
            f'the hold after the {r.size:+.0f} deg step ends in a limit cycle'


@pytest.mark.slow
def test_the_calibrated_controller_settles_on_the_physics_plant(arm, calibrated):
    out, payload = calibrated
    assert payload['closed_loop']['passed']
    # The convex map is inverted as a table from its own dead-zone edges.
    model = load_model(out / 'model.yaml')
    spec = load_controller(out / 'controller.yaml')
    assert isinstance(spec.idz, TableInverseDeadZone)
    assert model.dead_zone is None or spec.idz.dead_zone == pytest.approx(model.dead_zone)
    assert_settles(arm, out / 'controller.yaml', LEVELS)


@pytest.mark.slow
def test_a_pwm_arm_logged_stroke_by_stroke_is_calibrated_and_settles(tmp_path):
    machine = load_machine(shipped_config('physics_arm_pwm.yaml'))

    def runs(duties):
        return [run for duty in duties
                for run in full_stroke_runs(machine, DT, (duty,), seed=duty)]
    result = calibrate(runs(ESTIMATION), runs(VALIDATION),
                       CalibrationSettings(input_limits=(0.0, 100.0)))
    assert result.check.passed, result.warnings
    # The rest command it writes holds the true valve closed (overlap: 31.25-68.75 %).
    assert result.spec.v_limits == (0.0, 100.0) and 31.25 < result.spec.idz.rest < 68.75
    path = save_controller(result.spec, tmp_path / 'controller.yaml')
    assert_settles(machine, path, (-20.0, 5.0, 25.0, 0.0, -25.0, -5.0))

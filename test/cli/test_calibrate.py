"""hydro-sdp calibrate: from recordings of a lagged joint to a controller that holds on it."""

from contextlib import redirect_stdout
from dataclasses import replace
import io
import json
from pathlib import Path

from hydro_sdp.bags import write_bag
from hydro_sdp.cli.calibrate import describe, read_inputs
from hydro_sdp.cli.main import build_parser, main
from hydro_sdp.core import calibration as core_calibration
from hydro_sdp.core.calibration import calibrate, CalibrationSettings, split_records
from hydro_sdp.core.control.controller_spec import design_from_model
from hydro_sdp.core.control.design_plant import completed_poles
from hydro_sdp.core.control.idz_design import chord_map
from hydro_sdp.core.control.loop_check import (
    check_loop, CheckSettings, slower_poles, stroke_levels)
from hydro_sdp.core.control.loop_simulation import (
    LoopJoint, run_closed_loop, step_metrics, step_setpoints)
from hydro_sdp.core.diagnosis.results import Signature
from hydro_sdp.core.model.effects import ValveLag
from hydro_sdp.core.model.records import Record
from hydro_sdp.core.model.static_maps import chord_commands, linearise, PwlMap
from hydro_sdp.core.synthetic.joint_experiments import experiment_record
from hydro_sdp.io.controller_files import load_controller
from hydro_sdp.io.documents import load_yaml
from hydro_sdp.io.model_files import load_model
from hydro_sdp.plots import (
    command_unit_of, plot_closed_loop, plot_record, plot_signature, plot_velocity_map)
from hydro_sdp.report import calibration as report_calibration
import numpy as np
import pytest

pytestmark = [pytest.mark.usefixtures('figures_not_drawn')]

#: The hidden valve lag of the "measured" joint, s.
LAG = 0.12


def run(capsys, *argv):
    code = main([str(a) for a in argv])
    captured = capsys.readouterr()
    return code, captured.out, captured.err


@pytest.fixture(scope='module')
def truth(j2):
    """Return the true joint: J2 with a valve lag the identified model does not know."""
    return j2.with_effect(ValveLag(LAG))


@pytest.fixture(scope='module')
def records(truth):
    """Return steps for identification and two random-level runs."""
    return (experiment_record(truth, 'steps', seed=1, duration=60.0),
            experiment_record(truth, 'random', seed=2, duration=40.0),
            experiment_record(truth, 'random', seed=3, duration=40.0))


@pytest.fixture(scope='module')
def bags(records, tmp_path_factory):
    """Write the records as bags."""
    folder = tmp_path_factory.mktemp('lagged')
    return [str(write_bag(folder / name, [record]))
            for name, record in zip(('steps', 'random_1', 'random_2'), records)]


@pytest.fixture(scope='module')
def calibrated(bags, tmp_path_factory):
    """Run calibrate on the bags; return the output folder and the JSON object."""
    out = tmp_path_factory.mktemp('calibrated') / 'arm'
    stdout = io.StringIO()
    with redirect_stdout(stdout):
        code = main(['calibrate', bags[0], bags[1], '--validation', bags[2],
                     '--input-limits', '-10', '10', '--out', str(out), '--json'])
    assert code == 0
    return out, json.loads(stdout.getvalue())


@pytest.mark.slow
def test_calibrate_names_the_lag_and_its_controller_holds_on_the_true_joint(
        calibrated, bags, truth, capsys):
    out, payload = calibrated
    assert set(payload) >= {'model', 'controller', 'params', 'report', 'effect', 'mae',
                            'closed_loop', 'warnings'}
    assert payload['effect'] == 'valve_lag'
    assert set(payload['mae']) >= {'identified', 'final'}
    # identify fits a lag together with the dead time, so the diagnosis has little left to
    # add: the final model is no worse, and it carries a valve lag.
    assert payload['mae']['final'] <= payload['mae']['identified'] < 1.0
    assert isinstance(load_model(payload['model']).effect(ValveLag.name), ValveLag)
    steps = payload['closed_loop']
    assert len(steps['settling_time']) == len(steps['overshoot']) == 4
    assert steps['passed'] and max(steps['overshoot']) < 10.0
    # The paper's chord pulses at hold on the lagged joint (0.72 pulses/s, settling in
    # 2.7-2.9 s); faded in, it holds still and settles in 3.4-3.5 s (methods.md 5.7).
    assert [w.split(' (')[0] for w in payload['warnings']] == ['the IDZ pulses at hold']
    band, fade = steps['trade']
    assert not band['passed'] and band['pulse_rate'] > steps['chatter']['pulse_bound']
    assert fade['passed'] and fade['fade'] > 0.0 and fade['pulse_rate'] == 0.0
    assert steps['idz_fades'] == [0.0, fade['fade']] and steps['idz_forms'] == ['chord'] * 2
    assert steps['chatter']['pulse_rate'] == fade['pulse_rate']
    model = load_model(payload['model'])
    assert model.effect('valve_lag') is not None and model.input_limits == (-10.0, 10.0)
    # The written controller on the TRUE joint, simulated without the written model.
    spec = load_controller(payload['controller'])
    setpoint = step_setpoints([30.0, 50.0, 30.0], 10.0, 0.01)
    trace = run_closed_loop([LoopJoint(truth, spec.controller(), setpoint, 10.0)],
                            dt=0.01, control_period=spec.control_period)[0]
    metrics = step_metrics(trace, initial=10.0)
    assert [round(m.size) for m in metrics] == [20, 20, -20]
    for m in metrics:
        assert m.settling_time < 6.0 and m.overshoot < 10.0
    # The parameter file loads and points at the files written, by absolute path.
    params = load_yaml(payload['params'])
    assert set(params) == {'/**/pip_controller', '/**/hydro_plant', '/**/sdp_identifier'}
    controller = params['/**/pip_controller']['ros__parameters']
    assert controller == {'model_file': str(out.resolve() / 'model.yaml'),
                          'controller_file': str(out.resolve() / 'controller.yaml')}
    for node in params.values():
        path = Path(node['ros__parameters']['model_file'])
        assert path.is_absolute() and path.is_file()
    report = Path(payload['report'])
    for name in ('summary.md', 'velocity_map.png', 'evaluation.png', 'closed_loop.png',
                 'ramp.png', 'diagnosis/gap.png'):
        assert (report / name).is_file(), name
    # identify already carries the lag, so the diagnosis names nothing and draws no signature.
    assert not (report / 'diagnosis' / 'signature.png').exists()
    summary = (report / 'summary.md').read_text()
    assert 'valve_lag' in summary and 'dead-zone [' in summary and '] V;' in summary
    assert sorted(p.name for p in out.parent.iterdir()) == ['arm']  # no temporary left
    # A second run into the same folder is refused, and leaves it as it was.
    before = sorted(p.name for p in out.iterdir())
    code, _, err = run(capsys, 'calibrate', bags[0], '--out', out)
    assert code == 2 and 'use --force' in err and err.count('\n') == 1
    assert sorted(p.name for p in out.iterdir()) == before


@pytest.mark.slow
def test_csv_logs_calibrate_as_their_bags_do(records, calibrated, tmp_path, capsys):
    paths = []
    for name, record in zip(('steps', 'random_1', 'random_2'), records):
        # The logger's command on row k acts after it: it is the record's v_{k+1}.
        command = np.r_[record.v[1:], record.v[-1]]
        rows = ['time,angle_deg,duty'] + [
            f'{t!r},{y!r},{v!r}'
            for t, y, v in zip(record.t.tolist(), record.y.tolist(), command.tolist())]
        path = tmp_path / f'{name}.csv'
        path.write_text('\n'.join(rows) + '\n')
        paths.append(path)
    code, stdout, err = run(capsys, 'calibrate', paths[0], paths[1], '--validation', paths[2],
                            '--joint', 'j2', '--time', 'time', '--angle', 'angle_deg',
                            '--command', 'duty', '--input-limits', -10, 10,
                            '--out', tmp_path / 'from_csv', '--json')
    assert code == 0, err
    payload = json.loads(stdout)
    reference = calibrated[1]
    assert payload['effect'] == reference['effect'] == 'valve_lag'
    assert payload['mae']['final'] == pytest.approx(reference['mae']['final'], rel=1e-3)
    model, expected = load_model(payload['model']), load_model(reference['model'])
    assert model.delay == expected.delay and model.kind == expected.kind
    assert model.dead_zone == pytest.approx(expected.dead_zone, rel=1e-3)


#: Dominant poles too fast for the lagged joint.
FAST = (0.75 + 0.1j, 0.75 - 0.1j)


@pytest.fixture(scope='module')
def redesigned(records):
    """Calibrate from poles too fast for the lag (one diagnosis round, to be quick)."""
    return calibrate(records[:2], [records[2]], CalibrationSettings(poles=FAST, iterations=1))


@pytest.mark.slow
def test_a_failed_check_designs_again_with_slower_poles(redesigned):
    result = redesigned
    assert result.effect == 'valve_lag'
    assert len(result.designs) >= 2 and result.designs[0][:2] == ('0.75+0.1j', '0.75-0.1j')
    assert result.check.passed
    assert any('designed again with slower poles' in w for w in result.warnings)
    # The sdp map starts with the paper's chords; when they fail, the table takes over.
    assert result.forms[0] == 'chord' and set(result.forms[1:]) == {'table'}
    assert any('the IDZ inverts the sdp map itself (a table) instead' in w
               for w in result.warnings)
    first = design_from_model(result.model, form='table', poles=completed_poles(
        result.spec.plant, FAST), noise_std=result.identification.segmentation.noise_std)
    assert not check_loop(result.model, first, result.stroke, settings=CheckSettings(
        noise_std=result.identification.segmentation.noise_std)).passed
    # The dominant poles of the design kept are slower than the ones asked for.
    assert min(abs(p) for p in result.spec.poles if abs(p) > 0.5) > 0.76


@pytest.mark.slow
def test_a_failure_while_writing_leaves_nothing(redesigned, bags, tmp_path, capsys,
                                                monkeypatch):
    monkeypatch.setattr(core_calibration, 'calibrate', lambda *args, **kwargs: redesigned)

    def full_disk(folder, result, unit):
        (folder / 'summary.md').parent.mkdir(parents=True)
        (folder / 'summary.md').write_text('half')
        raise OSError('No space left on device')
    monkeypatch.setattr(report_calibration, 'write_report', full_disk)
    out = tmp_path / 'out'
    code, _, err = run(capsys, 'calibrate', bags[0], '--out', out)
    assert code == 2 and 'No space left' in err
    assert list(tmp_path.iterdir()) == []
    # With --force an existing folder is replaced, whole, only once the new one is complete.
    out.mkdir()
    (out / 'old.txt').write_text('old')
    code, _, _ = run(capsys, 'calibrate', bags[0], '--out', out, '--force')
    assert code == 2 and (out / 'old.txt').read_text() == 'old'
    monkeypatch.undo()
    monkeypatch.setattr(core_calibration, 'calibrate', lambda *args, **kwargs: redesigned)
    code, stdout, err = run(capsys, 'calibrate', bags[0], '--out', out, '--force', '--json')
    assert code == 0, err
    assert sorted(p.name for p in out.iterdir()) == ['controller.yaml', 'model.yaml',
                                                     'params.yaml', 'report']
    assert sorted(p.name for p in tmp_path.iterdir()) == ['out']
    warnings = json.loads(stdout)['warnings']
    assert any('designed again with slower poles' in w for w in warnings)


@pytest.mark.slow
def test_a_check_no_design_passes_says_what_stands_in_the_way(records):
    # A band no loop holds: every design fails, and so does every idealised check.
    impossible = CheckSettings(band=0.005)
    result = calibrate(records[:2], [records[2]],
                       CalibrationSettings(iterations=0, check=impossible))
    assert not result.check.passed and len(result.designs) == core_calibration.REDESIGNS + 2
    elements = [o.element for o in result.obstacles]
    assert elements[:2] == ['map', 'delay'] and 'noise' not in elements
    assert result.in_the_way == () and result.warnings[-1].startswith(
        'in the way: no element alone (the check with each idealised: map (')
    payload = describe(result, Path('out'))['closed_loop']
    assert payload['in_the_way'] == [] and set(payload['idealised']) == set(elements)
    assert payload['idz_forms'][:2] == ['chord', 'table']
    lines = report_calibration.summary_lines(result, 'V', [])
    assert 'In the way: **no element alone**.' in lines


def test_slower_poles_move_the_dominant_poles_toward_one():
    poles = slower_poles([0.94 + 0.05j, 0.94 - 0.05j, 0.0, 0.1])
    assert poles[0] == pytest.approx(0.958 + 0.035j)
    assert poles[1] == pytest.approx(0.958 - 0.035j)
    assert poles[2:] == [0.0, 0.1]


def test_the_check_steps_across_the_stroke():
    assert stroke_levels((-10.0, 90.0)) == pytest.approx((10.0, 40.0, 70.0))
    with pytest.raises(Exception, match='increasing'):
        stroke_levels((5.0, 5.0))


def _record(index):
    t = np.arange(1, 11) * 0.01
    return Record(t, np.zeros(10), np.zeros(10), joint='j2', source=f'r{index}')


@pytest.mark.parametrize('count, held', [(2, ['r1']), (3, ['r2']), (6, ['r2', 'r5'])])
def test_validation_holds_out_whole_records(count, held):
    estimation, validation, note = split_records([_record(i) for i in range(count)])
    assert [r.source for r in validation] == held
    assert len(estimation) + len(validation) == count
    assert 'held out' in note and 'whole records' in note


def test_one_record_is_evaluated_in_sample():
    estimation, validation, note = split_records([_record(0)])
    assert estimation == validation and 'in-sample' in note


def test_unusable_data_exits_2_and_writes_nothing(tmp_path, capsys, j2):
    still = Record(np.arange(1, 2001) * 0.01, np.zeros(2000),
                   np.random.default_rng(1).normal(0.0, 0.03, 2000), joint='j2')
    bag = write_bag(tmp_path / 'still', [still])
    out = tmp_path / 'out'
    code, stdout, err = run(capsys, 'calibrate', bag, '--out', out, '--json')
    assert code == 2 and stdout == ''
    assert err.startswith('error: ') and err.count('\n') == 1
    assert not out.exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == ['still']


def test_a_csv_log_needs_its_columns(tmp_path, capsys):
    log = tmp_path / 'run.csv'
    log.write_text('t,angle,duty\n0.00,1.0,0\n0.01,1.1,50\n0.02,1.3,50\n')
    code, _, err = run(capsys, 'calibrate', log, '--out', tmp_path / 'out')
    assert code == 2 and '--joint, --angle, --command' in err
    # --time the file itself asks for: a plain table has no time of its own.
    code, _, err = run(capsys, 'calibrate', log, '--out', tmp_path / 'out', '--joint', 'arm',
                       '--angle', 'angle', '--command', 'duty')
    assert code == 2 and err == f'error: {log}: a CSV log needs its time column (--time)\n'
    args = build_parser().parse_args(['calibrate', str(log), '--out', 'x', '--joint', 'arm',
                                      '--time', 't', '--angle', 'angle', '--command', 'duty'])
    (record,), topic = read_inputs([str(log)], args, 'reading')
    assert topic is None   # a CSV log has no command topic
    assert record.joint == 'arm'
    np.testing.assert_allclose(record.y, [1.0, 1.1, 1.3])
    np.testing.assert_allclose(record.v, [0.0, 0.0, 50.0])  # a row's command acts after it
    assert not (tmp_path / 'out').exists()


@pytest.mark.parametrize('limits, given, unit', [
    ((0.0, 100.0), None, '%'), ((-100.0, 100.0), None, '%'), ((-10.0, 10.0), None, 'V'),
    ((-1000.0, 1000.0), None, 'input units'), (None, None, 'input units'),
    ((-1000.0, 1000.0), 'drive-demand', 'drive-demand'), ((0.0, 100.0), 'mA', 'mA')])
def test_command_unit_from_the_input_range_or_the_user(limits, given, unit):
    assert command_unit_of(limits, given) == unit


def test_figures_label_the_command_in_the_models_unit(j2):
    duty = j2.__class__(j2.joint, j2.static_map, j2.delay, input_limits=(-100.0, 100.0))
    figure = plot_velocity_map(duty)
    assert figure.axes[0].get_xlabel() == 'steady command v (%)'
    assert plot_velocity_map(j2).axes[0].get_xlabel() == 'steady command v (V)'
    record = Record(np.arange(1, 11) * 0.01, np.zeros(10), np.zeros(10), joint='j2')
    assert plot_record(record, duty).axes[1].get_ylabel() == 'command v (%)'
    assert plot_record(record).axes[1].get_ylabel() == 'command v (input units)'
    signature = Signature('dead_zone', 'command', 'delayed command', 0.01, np.zeros(50),
                          np.zeros(50), np.linspace(-1.0, 1.0, 50), np.zeros(0, dtype=int),
                          np.zeros(0))
    assert plot_signature(signature, command_unit='%').axes[0].get_xlabel() == \
        'delayed command (%)'
    spec = design_from_model(j2)
    trace = run_closed_loop([LoopJoint(j2, spec.controller(), np.full(20, 1.0), 0.0)],
                            dt=0.01, control_period=0.05)
    assert plot_closed_loop(trace, command_unit='%').axes[-1].get_ylabel() == 'valve v (%)'


def test_the_idz_of_any_map_inverts_its_chords(j2):
    pwl = replace(j2, static_map=PwlMap(knots=(-10.0, -2.0, 2.0, 10.0),
                                        speeds=(-24.0, 0.0, 0.0, 30.0)), input_limits=None)
    chord = chord_map(pwl, (-10.0, 10.0))
    assert chord.dead_zone == pytest.approx((-2.0, 2.0), abs=0.02)
    assert chord.slope == pytest.approx((3.0, 3.75), rel=0.01)
    # On an sdp map the chords are those `design` inverts.
    chord = chord_map(j2, (-10.0, 10.0))
    expected = linearise(j2.static_map, *chord_commands(j2.static_map))
    assert chord.dead_zone == pytest.approx(j2.dead_zone, abs=0.02)
    assert chord.slope == pytest.approx(expected.slope, rel=0.01)


@pytest.mark.ros
@pytest.mark.slow
def test_the_nodes_run_the_loop_from_the_parameter_file(calibrated):
    pytest.importorskip('rclpy')
    from hydro_sdp.ros.controller_node import PipControllerNode
    from hydro_sdp.ros.identifier_node import IdentifierNode
    from hydro_sdp.ros.plant_node import PlantNode
    from hydro_sdp.ros.testing import Lockstep, RosHarness
    from sensor_msgs.msg import JointState
    from std_msgs.msg import Float64

    out, payload = calibrated
    args = ['--ros-args', '--params-file', payload['params']]
    with RosHarness() as ros:
        plant = ros.add(PlantNode, cli_args=args)
        controller = ros.add(PipControllerNode, cli_args=args)
        identifier = ros.add(IdentifierNode, cli_args=args)
        assert plant.models == [load_model(out / 'model.yaml')]
        assert controller.spec == load_controller(out / 'controller.yaml')
        assert identifier.model == plant.models[0]
        helper = ros.helper('calibrated')
        states = []
        helper.create_subscription(JointState, 'joint_states', states.append, 100)
        publisher = helper.create_publisher(Float64, 'j2/setpoint', 10)
        loop = Lockstep(ros, plant, controllers=[controller], observers=[identifier])
        assert ros.spin_until(lambda: publisher.get_subscription_count() >= 1)
        publisher.publish(Float64(data=np.radians(20.0)))
        assert ros.spin_until(lambda: controller.setpoints_received == 1)
        loop.run(600)
        assert ros.spin_until(lambda: len(states) >= 600)
    angles = np.degrees([state.position[0] for state in states[:600]])
    assert abs(angles[-1] - 20.0) < 0.5 and np.max(angles) < 22.0

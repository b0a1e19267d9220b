"""The hydro-sdp command line: outputs, exit codes, atomic files."""

import json
from pathlib import Path
import shutil
import subprocess
import sys

from hydro_sdp.bags import read_bag, read_record
from hydro_sdp.cli.main import build_parser, main
from hydro_sdp.core.model.effects import ValveLag
from hydro_sdp.core.model.timing import SamplePeriod
from hydro_sdp.core.synthetic.joint_experiments import experiment_record
from hydro_sdp.io.model_files import default_model_path, load_model
import numpy as np
import pytest
from rosbags.rosbag2 import Writer

pytestmark = [pytest.mark.usefixtures('figures_not_drawn')]


def run(capsys, *argv):
    code = main(list(argv))
    captured = capsys.readouterr()
    return code, captured.out, captured.err


@pytest.mark.parametrize('program', ['steps', 'random'])
def test_simulate_writes_a_bag_identify_can_read(tmp_path, capsys, program):
    code, out, err = run(capsys, 'simulate', str(default_model_path()), '--program', program,
                         '--out', str(tmp_path / 'bag'), '--seed', '3', '--duration', '20',
                         '--json')
    assert code == 0, err
    payload = json.loads(out)
    assert payload['bag'] == str(tmp_path / 'bag')
    record = read_record(tmp_path / 'bag')
    assert payload['samples'] == len(record)
    if program == 'random':
        assert len(record) == 2000
    model = load_model(default_model_path())
    assert np.all(record.y > model.angle_limits[0] - 0.5)
    assert np.std(np.diff(record.y)[record.v[:-1] == 0.0]) > 0.0   # measurement noise is there


def test_simulate_is_seeded(tmp_path, capsys):
    for name in ('a', 'b'):
        assert run(capsys, 'simulate', str(default_model_path()), '--program', 'random',
                   '--out', str(tmp_path / name), '--seed', '7', '--duration', '5')[0] == 0
    a, b = read_record(tmp_path / 'a'), read_record(tmp_path / 'b')
    np.testing.assert_array_equal(a.y, b.y)


def test_human_output(tmp_path, capsys):
    code, out, _ = run(capsys, 'simulate', str(default_model_path()), '--program', 'steps',
                       '--out', str(tmp_path / 'bag'), '--storage', 'mcap', '--duration', '10')
    assert code == 0
    assert out.startswith(f'wrote {tmp_path / "bag"} (mcap): ')


@pytest.mark.parametrize(('argv', 'message'), [
    (['simulate', 'absent.yaml', '--program', 'steps', '--out', 'x'],
     'error: absent.yaml: no such file'),
    (['simulate', '{model}', '--program', 'steps', '--out', '{file}/bag'], 'plain'),
])
def test_bad_input_exits_2_with_one_line(tmp_path, capsys, argv, message):
    (tmp_path / 'plain').write_text('not a folder')
    argv = [a.format(model=default_model_path(), file=tmp_path / 'plain') for a in argv]
    code, out, err = run(capsys, *argv)
    assert code == 2
    assert out == ''
    assert err.startswith('error: ') and message in err
    assert err.count('\n') == 1 and 'Traceback' not in err


@pytest.mark.parametrize('argv', [
    ['simulate', 'm.yaml', '--program', 'zigzag', '--out', 'x'],
    ['simulate', 'm.yaml', '--program', 'steps', '--out', 'x', '--duration', '-1'],
    ['simulate', 'm.yaml', '--program', 'steps', '--out', 'x', '--sample-period', 'nan'],
    ['simulate', 'm.yaml', '--program', 'steps'],
    ['nonsense'],
])
def test_bad_arguments_exit_2(capsys, argv):
    with pytest.raises(SystemExit) as exit_info:
        main(argv)
    assert exit_info.value.code == 2
    assert 'error:' in capsys.readouterr().err


@pytest.mark.parametrize('bad', ['0', '-0.01', 'nan', 'inf'])
@pytest.mark.parametrize('argv', [
    ['simulate', 'm.yaml', '--program', 'steps', '--out', 'x', '--sample-period'],
    ['closed-loop', 'm.yaml', '--setpoints', '10', '--sample-period'],
    ['closed-loop', 'm.yaml', '--setpoints', '10', '--control-period'],
    ['design', 'm.yaml', '--sample-period'],
    ['design', 'm.yaml', '--control-period'],
    ['calibrate', 'b', '--control-period'],
], ids=lambda argv: f'{argv[0]} {argv[-1]}')
def test_a_bad_period_option_is_a_usage_error_naming_it(capsys, argv, bad):
    with pytest.raises(SystemExit) as exit_info:
        main([*argv, bad])
    assert exit_info.value.code == 2
    err = capsys.readouterr().err
    assert err.endswith(f'error: argument {argv[-1]}: must be a positive number of seconds, '
                        f"got '{bad}'\n")


def test_period_options_give_sample_periods():
    parser = build_parser()
    args = parser.parse_args(['design', 'm.yaml', '--sample-period', '0.02'])
    assert type(args.sample_period) is SamplePeriod and args.sample_period == 0.02
    assert type(args.control_period) is SamplePeriod and args.control_period == 0.05


def test_bad_model_file_names_the_key(tmp_path, capsys):
    model = tmp_path / 'model.yaml'
    model.write_text(default_model_path().read_text().replace('delay: 0.15', 'delay: -1'))
    code, _, err = run(capsys, 'simulate', str(model), '--program', 'steps', '--out',
                       str(tmp_path / 'bag'))
    assert code == 2
    assert "key 'delay'" in err


def test_interrupted_run_leaves_no_partial_file(tmp_path, capsys, monkeypatch):
    calls = []

    def interrupt(self, connection, timestamp, data):
        calls.append(timestamp)
        if len(calls) > 1000:
            raise KeyboardInterrupt

    monkeypatch.setattr(Writer, 'write', interrupt)
    code, _, err = run(capsys, 'simulate', str(default_model_path()), '--program', 'steps',
                       '--out', str(tmp_path / 'bag'))
    assert code == 130
    assert 'interrupted' in err
    assert list(tmp_path.iterdir()) == []


def test_help_teaches(capsys):
    for argv in (['--help'], ['simulate', '--help'], ['demo', '--help']):
        with pytest.raises(SystemExit) as exit_info:
            main(argv)
        assert exit_info.value.code == 0
        out = capsys.readouterr().out
        assert 'example' in out or 'start with' in out


def test_console_script_runs_without_a_traceback(tmp_path):
    script = shutil.which('hydro-sdp', path=str(Path(sys.executable).parent))
    if script is None:
        pytest.skip('hydro-sdp is not installed in this environment')
    result = subprocess.run([script, 'simulate', str(tmp_path / 'absent.yaml'), '--program',
                             'steps', '--out', str(tmp_path / 'bag')],
                            capture_output=True, text=True, timeout=60)
    assert result.returncode == 2
    assert result.stderr == f'error: {tmp_path / "absent.yaml"}: no such file\n'


def test_design_writes_a_controller_the_loop_loads(tmp_path, capsys):
    controller = tmp_path / 'controller.yaml'
    code, out, err = run(capsys, 'design', str(default_model_path()), '--poles', '0.94+0.05j',
                         '0.94-0.05j', '0', '0', '--v-range', '-2.2', '1.75', '--u-limits',
                         '-2.5', '2.5', '--out', str(controller), '--plot',
                         str(tmp_path / 'idz.png'), '--json')
    assert code == 0, err
    payload = json.loads(out)
    for key in ('f', 'g', 'kI', 'poles', 'control_period', 'delay_samples', 'slopes',
                'dead_zone', 'u_limits'):
        assert key in payload
    assert payload['poles'] == ['0.94+0.05j', '0.94-0.05j', '0+0j', '0+0j']
    assert payload['f'][0] == pytest.approx(0.1261, abs=1e-4)
    assert payload['slopes'] == pytest.approx([1.1746, 2.3951], abs=1e-4)
    assert payload['delay_samples'] == 3
    assert (tmp_path / 'idz.png').read_bytes()[:4] == b'\x89PNG'
    code, out, err = run(capsys, 'closed-loop', str(default_model_path()), '--controller',
                         str(controller), '--setpoints', '20', '-10', '--hold', '8',
                         '--out', str(tmp_path / 'loop'), '--plot', str(tmp_path / 'loop.png'),
                         '--json')
    assert code == 0, err
    result = json.loads(out)
    assert result['settling_time'] < 5.0 and result['overshoot'] < 10.0
    assert abs(result['steady_error']) < 0.5
    assert [step['size'] for step in result['steps']] == [20.0, -30.0]
    data = read_bag(tmp_path / 'loop')
    assert set(data.floats) == {'/j2/valve_command', '/j2/setpoint'}
    record = data.record()
    assert len(record) == 1600
    np.testing.assert_allclose(np.degrees(data.floats['/j2/setpoint'].data[-1]), -10.0)


def test_design_refuses_bad_poles(capsys):
    code, _, err = run(capsys, 'design', str(default_model_path()), '--poles', '0.9', '0.9')
    assert code == 2 and 'needs 4 poles' in err
    with pytest.raises(SystemExit):
        main(['design', str(default_model_path()), '--poles', 'abc'])
    assert 'expected a complex number' in capsys.readouterr().err


def test_closed_loop_refuses_a_controller_of_another_joint(tmp_path, capsys):
    controller = tmp_path / 'c.yaml'
    assert run(capsys, 'design', str(default_model_path()), '--out', str(controller))[0] == 0
    other = tmp_path / 'boom.yaml'
    other.write_text(default_model_path().read_text().replace('joint: j2', 'joint: boom'))
    code, _, err = run(capsys, 'closed-loop', str(other), '--controller', str(controller),
                       '--setpoints', '10', '--out', str(tmp_path / 'bag'))
    assert code == 2 and "controller is for joint 'j2'" in err
    assert not (tmp_path / 'bag').exists()


def test_identify_and_evaluate_from_bags(tmp_path, capsys):
    model = str(default_model_path())
    assert run(capsys, 'simulate', model, '--program', 'steps', '--out',
               str(tmp_path / 'steps'), '--seed', '1')[0] == 0
    for seed in (2, 3):
        assert run(capsys, 'simulate', model, '--program', 'random', '--duration', '40',
                   '--out', str(tmp_path / f'run{seed}'), '--seed', str(seed))[0] == 0
    code, out, err = run(capsys, 'identify', str(tmp_path / 'steps'), '--out',
                         str(tmp_path / 'model.yaml'), '--angle-limits', '-13.8', '63.6',
                         '--input-limits', '-10', '10', '--plot-dir', str(tmp_path / 'figs'),
                         '--json')
    assert code == 0, err
    payload = json.loads(out)
    for key in ('format', 'joint', 'kind', 'delay', 'angle_limits', 'input_limits', 'dead_zone',
                'saturation_velocity', 'curvature', 'effects', 'alpha', 'sample_period',
                'experiments', 'mae'):
        assert key in payload
    assert payload['kind'] == 'sdp' and payload['delay'] == 0.15
    np.testing.assert_allclose(payload['alpha'], (-0.2951, 1.3560, -1.3298, 0.3887, 1.7710,
                                                  1.3124), rtol=0.01)
    assert payload['experiments']['used'] == 40
    identified = load_model(tmp_path / 'model.yaml')
    assert identified.angle_limits == (-13.8, 63.6)
    for name in ('step_responses.png', 'gains.png', 'velocity_map.png'):
        assert (tmp_path / 'figs' / name).read_bytes()[:4] == b'\x89PNG'
    code, out, err = run(capsys, 'evaluate', str(tmp_path / 'run2'), str(tmp_path / 'run3'),
                         '--model', str(tmp_path / 'model.yaml'), '--json')
    assert code == 0, err
    result = json.loads(out)
    assert set(result['mae']) == {'model', 'sdp_dz', 'linear'}
    assert result['mae']['model'] < result['mae']['sdp_dz'] < result['mae']['linear']
    assert len(result['records']) == 2


def test_identify_refuses_data_without_excitation(tmp_path, capsys):
    flat = tmp_path / 'flat.yaml'
    flat.write_text(default_model_path().read_text().replace(
        'dead_zone: [-1.3298, 1.3124]', 'dead_zone: [-9.5, 9.5]'))
    assert run(capsys, 'simulate', str(flat), '--program', 'steps', '--duration', '30',
               '--out', str(tmp_path / 'bag'))[0] == 0
    code, out, err = run(capsys, 'identify', str(tmp_path / 'bag'))
    assert code == 2 and out == ''
    assert err.startswith('error: no excitation')
    code, _, err = run(capsys, 'identify', str(tmp_path / 'bag'), '--joint', 'elbow')
    assert code == 2 and "joint 'elbow' is not in /joint_states" in err


def test_diagnose_names_the_effect_and_writes_the_report(tmp_path, capsys):
    truth = load_model(default_model_path()).with_effect(ValveLag(0.15))
    from hydro_sdp.bags import write_bag
    for index, seed in enumerate((3, 4, 5)):
        write_bag(tmp_path / f'run{index}',
                  [experiment_record(truth, 'random', seed=seed, duration=40.0)])
    code, out, err = run(capsys, 'diagnose', str(tmp_path / 'run0'), str(tmp_path / 'run1'),
                         '--validation', str(tmp_path / 'run2'), '--model',
                         str(default_model_path()), '--out', str(tmp_path / 'augmented.yaml'),
                         '--report', str(tmp_path / 'report'), '--json')
    assert code == 0, err
    payload = json.loads(out)
    assert payload['effect'] == 'valve_lag'
    assert payload['mae_after'] < 0.5 * payload['mae_before']
    assert payload['candidates'][0]['effect'] == 'valve_lag'
    # Both figures of the named word: held out, and on the runs the model came from.
    named = payload['candidates'][0]
    assert named['carries_over'] and named['refused'] == ''
    assert named['windowed_after'] < named['windowed_before']
    assert named['own_after'] <= named['own_before'] * 1.05
    assert payload['ledger'][0]['parameters']['time_constant'] == pytest.approx(0.15, rel=0.05)
    augmented = load_model(tmp_path / 'augmented.yaml')
    assert augmented.effect('valve_lag') is not None
    summary = (tmp_path / 'report' / 'summary.md').read_text()
    assert '**Named effect: `valve_lag`.**' in summary
    for name in ('gap.png', 'ledger.png', 'signature.png'):
        assert (tmp_path / 'report' / name).read_bytes()[:4] == b'\x89PNG'

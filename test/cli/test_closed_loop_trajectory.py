"""``hydro-sdp closed-loop --trajectory``: boom and dipper following a ramp and a tip line."""

import json

from hydro_sdp.bags import read_bag
from hydro_sdp.cli.main import main
from hydro_sdp.core.control.controller_spec import design_from_model
from hydro_sdp.core.control.loop_simulation import LoopJoint, run_closed_loop, step_setpoints
from hydro_sdp.io.documents import shipped_config
import numpy as np
import pytest

BOOM, DIPPER = str(shipped_config('lucie_boom.yaml')), str(shipped_config('lucie_dipper.yaml'))
RAMP = """\
format: hydro_sdp/trajectory/v1
joint_names: [boom, dipper]
points:
  - {time_from_start: 0.0, positions: [0.0, -100.0]}
  - {time_from_start: 4.0, positions: [30.0, -60.0]}
"""


def run(capsys, *argv):
    code = main(list(argv))
    captured = capsys.readouterr()
    return code, captured.out, captured.err


@pytest.fixture
def ramp(tmp_path):
    path = tmp_path / 'ramp.yaml'
    path.write_text(RAMP)
    return path


def test_boom_and_dipper_follow_a_ramp_with_feedforward(tmp_path, capsys, ramp):
    results = {}
    for flag in ('--feedforward', '--no-feedforward'):
        code, out, err = run(capsys, 'closed-loop', BOOM, DIPPER, '--trajectory', str(ramp),
                             '--out', str(tmp_path / flag), '--settle', '4', '--json', flag)
        assert code == 0, err
        results[flag] = json.loads(out)
    fed, plain = results['--feedforward'], results['--no-feedforward']
    assert fed['joints'] == ['boom', 'dipper'] and fed['motion'] == [1.0, 5.0]
    for joint in ('boom', 'dipper'):
        assert fed['rms_error'][joint] < 1.5            # issue 15's target
        assert abs(fed['final_error'][joint]) < 0.5
        # The PIP alone lags the ramp by about f0 r / kI (7.5 deg/s on the boom: ~7 deg).
        assert plain['rms_error'][joint] > 5.0 * fed['rms_error'][joint]
    assert 'path_error_mm' not in fed
    data = read_bag(tmp_path / '--feedforward')
    assert {'/boom/valve_command', '/dipper/valve_command', '/boom/setpoint',
            '/dipper/setpoint'} <= set(data.floats)
    np.testing.assert_allclose(np.degrees(data.floats['/dipper/setpoint'].data[-1]), -60.0)


def test_the_bucket_tip_follows_the_shipped_line(tmp_path, capsys):
    code, out, err = run(capsys, 'closed-loop', BOOM, DIPPER, '--trajectory',
                         str(shipped_config('lucie_line.yaml')), '--out', str(tmp_path / 'bag'),
                         '--plot', str(tmp_path / 'line.png'), '--json')
    assert code == 0, err
    result = json.loads(out)
    assert result['path_error_mm']['max'] < 5.0
    assert 0.0 < result['path_error_mm']['rms'] <= result['path_error_mm']['max']
    assert max(result['rms_error'].values()) < 1.5
    assert max(abs(e) for e in result['final_error'].values()) < 0.5
    assert (tmp_path / 'line.png').read_bytes()[:4] == b'\x89PNG'


def test_csv_trajectory_and_text_report(tmp_path, capsys):
    path = tmp_path / 'ramp.csv'
    path.write_text('# boom only, dipper holds\ntime,boom\n0,0\n3,15\n')
    code, out, err = run(capsys, 'closed-loop', BOOM, DIPPER, '--trajectory', str(path),
                         '--out', str(tmp_path / 'bag'), '--settle', '3', '--start-at', '0.5')
    assert code == 0, err
    assert 'motion from 0.5 to 3.5 s' in out and 'feed-forward on' in out
    rows = {line.split()[0]: line.split()[1:] for line in out.splitlines()
            if line.startswith(('boom ', 'dipper '))}
    assert float(rows['boom'][0]) < 1.5 and abs(float(rows['boom'][1])) < 0.5
    # The dipper was not named: it holds mid-travel (0 lies outside its end stops).
    data = read_bag(tmp_path / 'bag')
    np.testing.assert_allclose(np.degrees(data.floats['/dipper/setpoint'].data), -90.0)


@pytest.mark.parametrize('text, message', [
    ('time,boom,stick\n0,0,0\n2,10,10\n', 'joints not controlled: stick'),
    ('time,boom\n0,0\n2,60\n', 'boom reaches 60 deg (allowed [-39.5, 49.5])'),
    ('time,boom\n0,0\n0,10\n', 'strictly increasing'),
    ('t,boom\n0,0\n', "header must be 'time,<joint>,...'"),
    ('time,boom\n0,zero\n', 'line 2: not numbers'),
])
def test_refused_trajectories(tmp_path, capsys, text, message):
    path = tmp_path / 'bad.csv'
    path.write_text(text)
    code, _, err = run(capsys, 'closed-loop', BOOM, DIPPER, '--trajectory', str(path),
                       '--out', str(tmp_path / 'bag'))
    assert code == 2 and message in err
    assert not (tmp_path / 'bag').exists()


def test_option_combinations_are_checked(tmp_path, capsys, ramp):
    out = str(tmp_path / 'bag')
    code, _, err = run(capsys, 'closed-loop', BOOM, '--out', out)
    assert code == 2 and 'give --setpoints or --trajectory' in err
    code, _, err = run(capsys, 'closed-loop', BOOM, DIPPER, '--setpoints', '10', '--out', out)
    assert code == 2 and '--setpoints drives one joint' in err
    code, _, err = run(capsys, 'closed-loop', BOOM, DIPPER, '--trajectory', str(ramp),
                       '--y0', '3', '--out', out)
    assert code == 2 and '--y0 goes with --setpoints' in err


def test_zero_feedforward_on_held_setpoints_leaves_the_loop_unchanged(j2):
    spec = design_from_model(j2)
    setpoint = step_setpoints([20.0], 6.0, 0.01)
    plain = run_closed_loop([LoopJoint(j2, spec.controller(), setpoint)], dt=0.01,
                            control_period=0.05, noise_std=0.05, seed=4)[0]
    fed = run_closed_loop([LoopJoint(j2, spec.controller(), setpoint, 0.0,
                                     np.zeros(setpoint.size))],
                          dt=0.01, control_period=0.05, noise_std=0.05, seed=4)[0]
    np.testing.assert_array_equal(fed.y, plain.y)
    np.testing.assert_array_equal(fed.v, plain.v)

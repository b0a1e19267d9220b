"""``hydro-sdp closed-loop`` clamps set-points as the node does, refuses unfitting controllers."""

import json

from hydro_sdp.bags import read_bag
from hydro_sdp.cli.main import main
from hydro_sdp.io.model_files import default_model_path
import numpy as np


def run(capsys, *argv):
    code = main(list(argv))
    captured = capsys.readouterr()
    return code, captured.out, captured.err


def test_setpoints_beyond_the_end_stops_are_clamped_with_a_warning(tmp_path, capsys):
    code, out, err = run(capsys, 'closed-loop', str(default_model_path()), '--setpoints', '30',
                         '90', '-20', '--hold', '1', '--out', str(tmp_path / 'bag'), '--json')
    assert code == 0, err
    assert 'warning: set-point 90 deg is beyond the end stops [-13.8, 63.6] less the margin ' \
           '0.5 deg; using 63.1 deg' in err
    assert 'set-point -20 deg' in err and 'using -13.3 deg' in err
    assert 'set-point 30' not in err
    steps = json.loads(out)['steps']
    np.testing.assert_allclose([s['size'] for s in steps], [30.0, 33.1, -76.4])
    setpoints = np.degrees(read_bag(tmp_path / 'bag').floats['/j2/setpoint'].data)
    np.testing.assert_allclose([setpoints.max(), setpoints.min()], [63.1, -13.3])
    code, out, err = run(capsys, 'closed-loop', str(default_model_path()), '--setpoints', '63.6',
                         '--hold', '1', '--setpoint-margin', '0', '--out',
                         str(tmp_path / 'bag0'), '--json')
    assert code == 0 and 'warning' not in err
    assert json.loads(out)['steps'][0]['size'] == 63.6


def test_a_controller_for_another_valve_range_is_refused(tmp_path, capsys):
    controller = tmp_path / 'c.yaml'
    percent = tmp_path / 'percent.yaml'
    percent.write_text(default_model_path().read_text().replace(
        'input_limits: [-10.0, 10.0]', 'input_limits: [-100.0, 100.0]'))
    assert run(capsys, 'design', str(percent), '--out', str(controller))[0] == 0
    code, _, err = run(capsys, 'closed-loop', str(default_model_path()), '--controller',
                       str(controller), '--setpoints', '10', '--out', str(tmp_path / 'bag'))
    assert code == 2
    assert 'controller commands the valve over [-100.0, 100.0], beyond the range ' \
           "[-10.0, 10.0] of the model of joint 'j2': design the controller from this model " \
           '(hydro-sdp design MODEL --out CONTROLLER)' in err
    assert not (tmp_path / 'bag').exists()

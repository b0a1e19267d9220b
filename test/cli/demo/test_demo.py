"""The demo: every stage of the pipeline on the built-in J2 joint, its report and figures."""

import json

from hydro_sdp.bags import read_record
from hydro_sdp.cli.main import main
import numpy as np
import pytest

pytestmark = [pytest.mark.slow]


def run(capsys, *argv):
    """Run the command line in this process; return its exit code, stdout and stderr."""
    code = main(list(argv))
    captured = capsys.readouterr()
    return code, captured.out, captured.err


def test_demo_writes_a_report(tmp_path, capsys):
    code, out, err = run(capsys, 'demo', '--out', str(tmp_path / 'report'), '--short', '--json')
    assert code == 0, err
    summary = json.loads(out)['summary']
    report = tmp_path / 'report'
    assert (report / 'summary.md').read_text().startswith('# hydro_sdp demo')
    for name in ('steps.png', 'step_responses.png', 'gains.png', 'velocity_map.png',
                 'evaluation.png', 'idz.png', 'closed_loop.png', 'two_joints.png',
                 'bucket_line.png', 'recalibration.png'):
        png = report / 'figures' / name
        assert png.read_bytes()[:8] == b'\x89PNG\r\n\x1a\n'
    assert read_record(summary['bags']['steps']).joint == 'j2'
    assert summary['control']['f'][0] == pytest.approx(0.1261, abs=1e-4)
    identified = summary['identification']
    np.testing.assert_allclose(identified['alpha'], identified['true_alpha'], rtol=0.01)
    mae = identified['mae']
    assert mae['model'] < mae['sdp_dz'] < mae['linear']
    recalibration = summary['recalibration']
    # The quiet sensor (0.01 deg) of the wear scenario: both edges updated, the first within
    # 5 s of the wear, to the worn dead-zone (test_identifier_node runs the noisiest sensor).
    assert recalibration['recalibrations'] >= 2
    assert recalibration['seconds_to_recalibration'] < 5.0
    np.testing.assert_allclose(recalibration['edges'], (-1.0298, 1.0124), atol=0.05)
    assert recalibration['error_recalibrated'] < 0.5 < recalibration['error_after_drift']
    diagnosis = summary['diagnosis']
    assert diagnosis['effect'] == 'valve_lag'
    assert diagnosis['mae_after'] < 0.5 * diagnosis['mae_before']
    assert (report / 'diagnosis' / 'summary.md').is_file()
    assert all(step['settling_time'] < 5.0 for step in summary['control']['steps'])
    assert (report / 'j2_controller.yaml').is_file()
    line = summary['bucket_line']
    assert set(line) == {'motion', 'path_error_mm', 'rms_error', 'final_error'}
    assert set(line['rms_error']) == set(line['final_error']) == {'boom', 'dipper'}
    # The shipped line is 0.99 m at 0.1 m/s, starting 1 s in.
    assert line['motion'] == pytest.approx([1.0, 1.0 + np.hypot(0.7, 0.7) / 0.1])
    path = line['path_error_mm']
    assert 0.0 < path['rms'] <= path['max'] < 5.0
    assert all(0.0 < error < 1.0 for error in line['rms_error'].values())
    assert '## A straight bucket path' in (report / 'summary.md').read_text()

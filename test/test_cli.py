"""The hydro-sdp command line: outputs, exit codes, atomic files."""

import json
from pathlib import Path
import shutil
import subprocess
import sys

from hydro_sdp.bags import read_record
from hydro_sdp.cli.main import main
from hydro_sdp.files import default_model_path, load_model
import numpy as np
import pytest
from rosbags.rosbag2 import Writer


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


def test_demo_writes_a_report(tmp_path, capsys):
    code, out, err = run(capsys, 'demo', '--out', str(tmp_path / 'report'), '--short', '--json')
    assert code == 0, err
    summary = json.loads(out)['summary']
    report = tmp_path / 'report'
    assert (report / 'summary.md').read_text().startswith('# hydro_sdp demo')
    for name in ('steps.png', 'random.png', 'velocity_map.png'):
        png = report / 'figures' / name
        assert png.read_bytes()[:8] == b'\x89PNG\r\n\x1a\n'
    assert read_record(summary['bags']['steps']).joint == 'j2'


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

"""``hydro-sdp sdp``: JSON, text, figures and bad input, on bags written by the package."""

import json
import os
from pathlib import Path
import re
import subprocess
import sys

from conftest import REPO
from hydro_sdp.bags import write_bag
from hydro_sdp.cli.main import main
from hydro_sdp.cli.sdp import STATE_NAMES
from hydro_sdp.core.identification.state_dependence import STATES
from hydro_sdp.core.model.records import Record
from hydro_sdp.io.model_files import save_model
import numpy as np
import pytest
from support.joint_generator import Joint, Machine, record, SpeedMap
from support.plain_joint import PlainJoint, steps

JOINT = {'lag': 0.05, 'slope': (22.0, 25.0), 'saturation': (45.0, 50.0), 'stops': (-90.0, 90.0)}
KEYS = {'state', 'direction', 'parameter', 'share', 'nvr', 'significant', 'p_value', 'grid',
        'estimate', 'se', 'constant', 'samples', 'given'}


def run(capsys, *argv):
    code = main([str(a) for a in argv])
    captured = capsys.readouterr()
    return code, captured.out, captured.err


def as_bag_record(record, joint='j2'):
    """Stamp the record from 0.02 s, as write_bag stores bags."""
    return Record(record.t - record.t[0] + 0.02, record.v, record.y, joint)


@pytest.fixture(scope='module')
def bags(tmp_path_factory):
    folder = tmp_path_factory.mktemp('sdp')
    joint = PlainJoint(**JOINT)
    # Twelve levels each way: with fewer, one step per level cannot rule out that each step
    # has a gain of its own (the test flips whole runs, methods.md section 14.5).
    sizes = np.linspace(1.0, 8.0, 12)
    paths = []
    for i in range(2):
        # Steps out and back: each level, then the same level the other way.
        record = joint.run(steps([size * sign for size in sizes[i::2] for sign in (1.0, -1.0)],
                                 hold=1.0), seed=i)
        paths.append(str(write_bag(folder / f'steps{i}', [as_bag_record(record)])))
    return paths


def test_the_arx_analysis_as_json(bags, capsys, tmp_path):
    code, out, err = run(capsys, 'sdp', *bags, '--states', 'command,angle', '--json',
                         '--plot-dir', tmp_path / 'figures')
    assert code == 0, err
    result = json.loads(out)
    assert result['target'] == 'arx' and result['samples'] > 1000
    assert set(result['a1']) == {'mean', 'se', 'nvr'}
    assert abs(result['a1']['mean'] + 1.0) < 0.01
    states = result['states']
    assert states[0]['state'] == 'command' and states[0]['significant']
    for entry in states:
        assert KEYS <= set(entry)
        assert len(entry['grid']) == len(entry['estimate']) == len(entry['se']) <= 60
        assert entry['grid'] == sorted(entry['grid'])
    shares = [e['share'] for e in states if e['state'] == 'angle']
    assert shares == sorted(shares, reverse=True)
    # The first state weighed alone, the angle by what it adds to it.
    assert {e['given'] for e in states} == {None, 'command'}
    assert all(e['given'] == 'command' for e in states if e['state'] == 'angle')
    assert result['residual'] == []
    assert {'state': 'since_change', 'reason': 'no --load-topic'} not in result['skipped']
    assert sorted(Path(p).name for p in result['plots']) == [
        'sdp_angle.png', 'sdp_command.png', 'sdp_shares.png']
    assert all(Path(p).stat().st_size > 10_000 for p in result['plots'])


def test_the_text_report_and_the_model_target(bags, capsys, tmp_path, j2):
    code, out, _ = run(capsys, 'sdp', *bags, '--states', 'command,load')
    assert code == 0
    assert out.startswith('SDP-ARX model')
    a1 = float(re.search(r'^a1 = (\S+) \+-', out, re.MULTILINE).group(1))
    assert abs(a1 + 1.0) < 0.01 and 'load not analysed: no --load-topic' in out
    assert 'first: b depends significantly on command' in out
    save_model(j2, tmp_path / 'j2.yaml')
    code, out, err = run(capsys, 'sdp', *bags, '--model', tmp_path / 'j2.yaml', '--states',
                         'command,since_change', '--replicates', '39', '--json')
    assert code == 0, err
    result = json.loads(out)
    assert result['target'] == 'ratio' and result['a1'] is None
    assert {e['parameter'] for e in result['states']} == {'ratio'}
    assert {e['parameter'] for e in result['residual']} == {'residual'}
    assert {e['state'] for e in result['residual']} == {'command', 'since_change'}


def test_increments_held_at_a_stop_are_left_out_and_counted(tmp_path, capsys):
    # A duty held against the top stop for 4 s after each full stroke.
    joint = Joint(SpeedMap('exp', (38.0, 62.0), (30.0, 35.0), (0.08, 0.09)), delay=0.12,
                  stops=(-35.0, 40.0), noise=0.02)
    v = np.r_[np.full(100, 50.0), np.full(600, 90.0), np.full(100, 50.0), np.full(700, 10.0),
              np.full(100, 50.0)]
    bag = write_bag(tmp_path / 'stops', [as_bag_record(record(Machine((joint,)), v[:, None],
                                                              angles0=[0.0], seed=3))])
    code, out, err = run(capsys, 'sdp', bag, '--states', 'command,since_change', '--json')
    assert code == 0, err
    left = {entry['reason']: entry['rows'] for entry in json.loads(out)['left_out']}
    assert left['held at an end stop while the command drives into it'] > 500
    code, out, _ = run(capsys, 'sdp', bag, '--states', 'command')
    assert code == 0
    assert re.search(r'^left out \d+ increments held at an end stop while the command drives '
                     r'into it$', out, re.MULTILINE)


def test_integrated_random_walks_find_the_same_first_state(bags, capsys):
    code, out, err = run(capsys, 'sdp', *bags, '--states', 'command,angle', '--irw', '--json')
    assert code == 0, err
    first = json.loads(out)['states'][0]
    assert first['state'] == 'command' and first['significant']


@pytest.mark.parametrize(('argv', 'message'), [
    (['--states', 'angle,speed'], "argument --states: unknown state 'speed'"),
    (['--states', 'angle,angle'], 'argument --states: a state is named twice'),
    (['--replicates', '5'], 'argument --replicates: need at least 19'),
])
def test_bad_options_exit_2_naming_the_option(bags, capsys, argv, message):
    with pytest.raises(SystemExit) as exit_info:
        main(['sdp', bags[0], *argv])
    assert exit_info.value.code == 2
    assert f'error: {message}' in capsys.readouterr().err


@pytest.mark.parametrize(('argv', 'message'), [
    (['--states', 'load'], 'error: no state to analyse: load needs --load-topic'),
    (['--model', 'absent.yaml'], 'error: absent.yaml: no such file'),
    (['--load-topic', '/missing'], 'error: '),
])
def test_bad_input_is_one_line_and_exit_2(bags, capsys, argv, message):
    code, out, err = run(capsys, 'sdp', bags[0], *argv)
    assert code == 2 and out == ''
    assert len(err.strip().splitlines()) == 1 and err.startswith(message), err


def test_a_joint_that_is_never_driven_is_refused(tmp_path, capsys):
    t = 0.01 * np.arange(2, 602)
    record = Record(t, np.zeros(t.size), np.random.default_rng(0).normal(0.0, 0.02, t.size),
                    'j2')
    bag = write_bag(tmp_path / 'still', [record])
    code, out, err = run(capsys, 'sdp', bag, '--states', 'command')
    assert code == 2 and out == ''
    assert err.startswith('error: ') and len(err.strip().splitlines()) == 1


def test_help_teaches_with_examples_and_names_every_state(capsys):
    with pytest.raises(SystemExit):
        main(['sdp', '--help'])
    text = capsys.readouterr().out
    assert 'examples:' in text and 'hydro-sdp sdp steps_bag' in text
    for name in STATES:
        assert name in text
    # The command line keeps its own list (its --help loads no scipy): the same states.
    assert STATE_NAMES == STATES


def test_help_loads_no_scipy_or_matplotlib(tmp_path):
    probe = ('import sys\nfrom hydro_sdp.cli.main import main\ntry:\n    main(["sdp", "--help"])\n'
             'except SystemExit:\n    pass\n'
             'print(sorted({n.split(".")[0] for n in sys.modules} & {"scipy", "matplotlib"}))')
    done = subprocess.run([sys.executable, '-c', probe], capture_output=True, text=True,
                          cwd=tmp_path, env=dict(os.environ, PYTHONPATH=str(REPO)), check=True,
                          timeout=120)
    assert done.stdout.strip().splitlines()[-1] == '[]'

"""Commands say which files they wrote, and what they were given apart from what they saw."""

import json

from hydro_sdp.io.model_files import default_model_path
import pytest
from support.cli_runs import run_cli


@pytest.fixture(scope='module')
def steps_bag(tmp_path_factory):
    folder = tmp_path_factory.mktemp('wrote')
    run_cli('simulate', default_model_path(), '--program', 'steps', '--duration', '40',
            '--out', folder / 'steps')
    return folder


def test_identify_and_design_list_the_figures_they_wrote(steps_bag):
    out = run_cli('identify', steps_bag / 'steps', '--out', steps_bag / 'm.yaml', '--plot-dir',
                  steps_bag / 'figs')
    for name in ('step_responses', 'gains', 'velocity_map'):
        assert f'wrote {steps_bag / "figs" / name}.png' in out
        assert (steps_bag / 'figs' / f'{name}.png').exists()
    out = run_cli('design', steps_bag / 'm.yaml', '--out', steps_bag / 'c.yaml', '--plot',
                  steps_bag / 'idz.png')
    assert f'wrote {steps_bag / "idz.png"}' in out and (steps_bag / 'idz.png').exists()


def test_stops_given_are_reported_as_given_and_the_valve_range_as_the_commands_seen(
        steps_bag):
    out = run_cli('identify', steps_bag / 'steps', '--angle-limits', '-13.8', '63.6')
    assert 'end stops given -13.80 deg, 63.60 deg (--angle-limits)' in out
    assert 'seen -13.80' not in out
    result = json.loads(run_cli('identify', steps_bag / 'steps', '--json'))
    assert result['end_stops_from'] == 'none' and result['angle_limits'] is None
    assert result['input_limits_from'] == 'data'
    assert result['input_limits'] == result['commands_seen']
    assert 'end stops none seen' in run_cli('identify', steps_bag / 'steps')


def test_the_line_run_says_when_the_motion_had_ended(tmp_path):
    config = default_model_path().parent
    out = run_cli('closed-loop', config / 'lucie_boom.yaml', config / 'lucie_dipper.yaml',
                  '--trajectory', config / 'lucie_line.yaml', '--out', tmp_path / 'line',
                  '--plot', tmp_path / 'line.png')
    assert 'after the motion ended (t > 10.90 s), while the joints settle at the end point' \
        in out
    assert f'wrote {tmp_path / "line.png"}' in out
    result = json.loads(run_cli('closed-loop', config / 'lucie_boom.yaml',
                                config / 'lucie_dipper.yaml', '--trajectory',
                                config / 'lucie_line.yaml', '--out', tmp_path / 'line2', '--json'))
    path = result['path_error_mm']
    assert path['after_motion'] > path['max']

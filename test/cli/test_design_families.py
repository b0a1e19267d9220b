"""hydro-sdp design on every map family identify writes; closed-loop runs what it writes."""

import json

from hydro_sdp.cli.main import main
from hydro_sdp.io.documents import load_yaml
from hydro_sdp.io.model_files import save_model
import pytest
from support.map_families import MODELS

#: The IDZ each family gets without --idz-form.
DEFAULT_FORMS = {'sdp': 'chord', 'sdp_dz': 'chord', 'linear': 'chord', 'pwl': 'table',
                 'poly': 'table', 'power_sat': 'table'}


def run(capsys, *argv):
    code = main([str(a) for a in argv])
    captured = capsys.readouterr()
    return code, captured.out, captured.err


@pytest.mark.parametrize('kind', sorted(MODELS))
def test_every_family_is_designed_and_its_file_runs_the_loop(kind, tmp_path, capsys):
    model = MODELS[kind]
    path = save_model(model, tmp_path / 'model.yaml')
    controller = tmp_path / 'controller.yaml'
    code, out, err = run(capsys, 'design', path, '--out', controller, '--json')
    assert code == 0, err
    payload = json.loads(out)
    assert payload['idz_form'] == DEFAULT_FORMS[kind]
    assert ('table' in load_yaml(controller)['idz']) == (DEFAULT_FORMS[kind] == 'table')
    code, out, err = run(capsys, 'closed-loop', path, '--controller', controller,
                         '--setpoints', 5, -5, '--hold', 6, '--out', tmp_path / 'bag',
                         '--json')
    assert code == 0, err
    # Both steps settle into +-0.5 deg on the model itself.
    assert all(step['settling_time'] is not None and step['settling_time'] < 6.0
               for step in json.loads(out)['steps'])


def test_both_forms_on_request_and_the_table_figure(tmp_path, capsys):
    path = save_model(MODELS['power_sat'], tmp_path / 'model.yaml')
    code, out, err = run(capsys, 'design', path, '--idz-form', 'chord', '--json')
    assert code == 0, err
    assert json.loads(out)['idz_form'] == 'chord'
    code, out, err = run(capsys, 'design', path, '--noise-std', '0.01', '--plot',
                         tmp_path / 'idz.png', '--json')
    assert code == 0, err
    payload = json.loads(out)
    assert payload['idz_form'] == 'table' and (tmp_path / 'idz.png').stat().st_size > 10000
    j2 = save_model(MODELS['sdp'], tmp_path / 'j2.yaml')
    code, out, err = run(capsys, 'design', j2, '--idz-form', 'table', '--json')
    assert code == 0 and json.loads(out)['idz_form'] == 'table'


def test_a_table_needs_a_command_range(tmp_path, capsys):
    bare = MODELS['linear'].__class__(joint='pwm', static_map=MODELS['linear'].static_map,
                                      delay=0.1)
    path = save_model(bare, tmp_path / 'model.yaml')
    code, _, err = run(capsys, 'design', path, '--idz-form', 'table')
    assert code == 2 and err.startswith('error: ') and 'input_limits (or --v-range)' in err
    assert '\n' not in err.strip()
    code, _, err = run(capsys, 'design', path, '--idz-form', 'table', '--v-range', '-5', '5')
    assert code == 0, err
    code, _, err = run(capsys, 'design', path, '--idz-form', 'table', '--v-range', '1', '5')
    assert code == 2 and 'rest command' in err
    with pytest.raises(SystemExit):
        main(['design', str(path), '--idz-form', 'tabel'])
    assert "invalid choice: 'tabel'" in capsys.readouterr().err

"""The model file remembers the command topic it was identified from; the commands use it."""

from dataclasses import replace
import json

from hydro_sdp.bags import inspect_bag, read_record, write_bag
from hydro_sdp.cli.main import main
from hydro_sdp.core.errors import DataError, ModelFileError
from hydro_sdp.core.model.joint_model import JointModel
from hydro_sdp.core.synthetic.joint_experiments import experiment_record
from hydro_sdp.io.model_files import load_model, save_model
import numpy as np
import pytest
from support.cli_runs import json_result

pytestmark = [pytest.mark.usefixtures('figures_not_drawn')]

TOPIC = '/boom/pwm'


def test_the_model_file_keeps_the_command_topic_next_to_the_joint(j2, tmp_path):
    model = replace(j2, command_topic='/arm/pwm')
    mapping = model.to_mapping()
    assert list(mapping)[:4] == ['format', 'joint', 'command_topic', 'kind']
    assert mapping['command_topic'] == '/arm/pwm'
    assert load_model(save_model(model, tmp_path / 'm.yaml')) == model
    # A file without the key (every file written before) loads unchanged and writes back
    # without it.
    old = j2.to_mapping()
    assert 'command_topic' not in old
    loaded = JointModel.from_mapping(dict(old))
    assert loaded.command_topic is None and loaded.to_mapping() == old
    # Effects keep the topic.
    assert model.without_effect('valve_lag').command_topic == '/arm/pwm'


@pytest.mark.parametrize('value', [3, '', '  ', '/arm pwm', ['/arm/pwm']])
@pytest.mark.parametrize('key', ['command_topic', 'load_topic'])
def test_a_bad_topic_is_refused_naming_the_key(j2, key, value):
    mapping = dict(j2.to_mapping(), **{key: value})
    with pytest.raises(ModelFileError, match=key):
        JointModel.from_mapping(mapping)


def test_the_model_file_keeps_the_load_topic(j2, tmp_path):
    model = replace(j2, command_topic='/arm/pwm', load_topic='/arm/pressure')
    mapping = model.to_mapping()
    assert list(mapping)[:5] == ['format', 'joint', 'command_topic', 'load_topic', 'kind']
    assert load_model(save_model(model, tmp_path / 'm.yaml')) == model
    assert 'load_topic' not in j2.to_mapping()


def test_diagnose_remembers_the_load_topic_and_evaluate_reads_it(tmp_path, capsys):
    from hydro_sdp.core.model.effects import LoadDependence
    from hydro_sdp.core.model.exogenous_signals import Exogenous
    from hydro_sdp.core.model.records import Record
    from hydro_sdp.core.model.simulation import simulate
    from hydro_sdp.core.model.static_maps import LinearMap
    # A linear joint 0.3 % faster per unit of load, in runs at four loads.
    model = JointModel('arm', LinearMap(gain=10.0), 0.05)
    hidden = LoadDependence(positive=0.003, negative=0.003, reference=0.0)
    rng = np.random.default_rng(2)
    bags = []
    for i, load in enumerate((0.0, 100.0, 200.0, 50.0)):
        v = np.r_[np.zeros(50), np.repeat(rng.choice([-2.0, -1.0, 1.0, 2.0], 20), 100)]
        t = 0.01 * np.arange(1, v.size + 1)
        y = simulate(replace(model, effects=(hidden,)), v, 0.01, 0.0,
                     exogenous=Exogenous(load=np.full(v.size, load)))
        y = y + rng.normal(0.0, 0.01, v.size)
        bags.append(str(write_bag(tmp_path / f'run{i}', [Record(t, v, y, 'arm')],
                                  setpoints={'arm_load': np.full(v.size, np.degrees(load))})))
    save_model(model, tmp_path / 'arm.yaml')
    assert main(['diagnose', *bags[:3], '--validation', bags[3], '--model',
                 str(tmp_path / 'arm.yaml'), '--load-topic', '/arm_load/setpoint',
                 '--iterations', '1', '--out', str(tmp_path / 'loaded.yaml'), '--json']) == 0
    assert json.loads(capsys.readouterr().out)['effect'] == 'load_dependence'
    loaded = load_model(tmp_path / 'loaded.yaml')
    assert loaded.load_topic == '/arm_load/setpoint'
    # evaluate reads the remembered topic: the load-dependent model fits the run at load
    # 50 that it never saw, the plain model does not.
    errors = {}
    for name in ('arm', 'loaded'):
        assert main(['evaluate', bags[3], '--model', str(tmp_path / f'{name}.yaml'),
                     '--json']) == 0
        errors[name] = json.loads(capsys.readouterr().out)['mae']['model']
    assert errors['loaded'] < 0.3 * errors['arm']


@pytest.fixture(scope='module')
def boom(j2):
    """Return the J2 joint named boom, and step and random records of it."""
    model = replace(j2, joint='boom')
    steps = experiment_record(model, 'steps', seed=4, duration=60.0)
    random = experiment_record(model, 'random', seed=5, duration=40.0)
    return model, steps, random


@pytest.fixture(scope='module')
def bags(boom, tmp_path_factory):
    """Write the records as bags whose command topic is /boom/pwm."""
    folder = tmp_path_factory.mktemp('pwm')
    _, steps, random = boom
    return (str(write_bag(folder / 'steps', [steps], command_topics={'boom': TOPIC})),
            str(write_bag(folder / 'random', [random], command_topics={'boom': TOPIC})))


def test_write_bag_writes_the_command_topic_given(boom, bags):
    _, steps, _ = boom
    topics = {topic.name for topic in inspect_bag(bags[0]).topics}
    assert TOPIC in topics and '/boom/valve_command' not in topics
    record = read_record(bags[0], 'boom', TOPIC)
    # Stamped as every command topic: read back as the command in force at each sample.
    np.testing.assert_array_equal(record.v, steps.v)
    np.testing.assert_allclose(record.y, steps.y, atol=1e-9)
    with pytest.raises(DataError, match='stick'):
        write_bag(bags[0] + '_x', [steps], command_topics={'stick': TOPIC})


@pytest.fixture(scope='module')
def identified(bags, tmp_path_factory):
    """Identify from the steps bag on /boom/pwm; return the model file."""
    out = tmp_path_factory.mktemp('identified') / 'boom.yaml'
    code, payload = json_result('identify', bags[0], '--command-topic', TOPIC, '--out', out)
    assert code == 0
    assert payload['command_topic'] == TOPIC
    return out


def test_identify_writes_the_topic_and_evaluate_and_diagnose_read_it(
        identified, bags, tmp_path):
    model = load_model(identified)
    assert model.joint == 'boom' and model.command_topic == TOPIC
    # evaluate as the README prints it (no --command-topic): the same scores as when given.
    code, remembered = json_result('evaluate', bags[1], '--model', identified)
    assert code == 0
    code, given = json_result('evaluate', bags[1], '--model', identified,
                              '--command-topic', TOPIC)
    assert code == 0
    assert remembered['mae'] == given['mae'] and remembered['mae']['model'] < 0.5
    # Without the key the bag has no valve_command topic: exit 2, as before.
    bare = save_model(replace(model, command_topic=None), tmp_path / 'bare.yaml')
    assert json_result('evaluate', bags[1], '--model', bare)[0] == 2
    # diagnose likewise; the model it writes keeps the topic.
    out = tmp_path / 'diagnosed.yaml'
    code, diagnosed = json_result('diagnose', bags[0], '--validation', bags[1], '--model',
                                  identified, '--iterations', '1', '--out', out)
    assert code == 0 and diagnosed['mae_before'] < 0.5
    assert load_model(out).command_topic == TOPIC
    assert json_result('diagnose', bags[0], '--model', bare)[0] == 2


def test_a_topic_given_on_the_command_line_wins(identified, bags, tmp_path):
    # The model remembers a topic the bag lacks, the user names the right one.
    model = replace(load_model(identified), command_topic='/boom/other')
    other = save_model(model, tmp_path / 'other.yaml')
    code, payload = json_result('evaluate', bags[1], '--model', other, '--command-topic', TOPIC)
    assert code == 0 and payload['mae']['model'] < 0.5


@pytest.mark.slow
def test_calibrate_writes_the_topic_and_identifies_at_the_rest_given(boom, tmp_path):
    # A valve whose neutral is 50 (commands 40..60): calibrate --rest 50 identifies there.
    _, steps, random = boom
    shifted = [replace(r, v=r.v + 50.0) for r in (steps, random)]
    bags = [str(write_bag(tmp_path / name, [r], command_topics={'boom': TOPIC}))
            for name, r in zip(('steps', 'random'), shifted)]
    out = tmp_path / 'boom'
    code, payload = json_result('calibrate', bags[0], '--validation', bags[1],
                                '--command-topic', TOPIC, '--rest', '50', '--input-limits',
                                '40', '60', '--out', out)
    assert code == 0
    assert payload['rest'] == 50.0
    model = load_model(out / 'model.yaml')
    assert model.command_topic == TOPIC and model.joint == 'boom'
    # Still at 50, moving both ways either side of it.
    assert abs(float(model.rate(50.0))) < 0.05
    assert float(model.rate(40.0)) < -1.0 < 1.0 < float(model.rate(60.0))
    # The README route: evaluate the written model on a bag without --command-topic.
    assert json_result('evaluate', bags[1], '--model', out / 'model.yaml')[0] == 0

"""
Bags as machines write them: stamps since 1970 with timer jitter, commands at their own rate.

The same J2 runs are written twice: as clean records (stamps from 0.01 s, each
command in step with its sample) and as ``ros2 bag record`` leaves a real machine's
(every stamp shifted by 1.76e9 s, +-0.5 ms of jitter, commands on their own 50 Hz
timer). identify, evaluate, diagnose and calibrate must give the same answers on
both, beyond noise; and nothing the plant does not have is added.
"""


from hydro_sdp.bags import read_bag, write_bag
from hydro_sdp.cli.common import read_records
from hydro_sdp.core.calibration import calibrate, CalibrationSettings
from hydro_sdp.core.diagnosis import diagnose
from hydro_sdp.core.identification.evaluation import evaluate
from hydro_sdp.core.identification.identify import identify
from hydro_sdp.core.model.records import Record
from hydro_sdp.core.model.simulation import simulate
from hydro_sdp.core.synthetic.programs import random_program, step_program
import numpy as np
import pytest
from support.recorded_stamps import (
    asynchronous_commands, EPOCH, program_of_samples, write_recorded_bag)

pytestmark = [pytest.mark.usefixtures('figures_not_drawn')]

DT = 0.01
NOISE = 0.02


def runs(j2):
    """Step and random programs of J2, per sample."""
    return {'steps': step_program(j2, DT, steps=16),
            'random_1': random_program(j2, DT, 25.0, seed=3),
            'random_2': random_program(j2, DT, 25.0, seed=4)}


@pytest.fixture(scope='module')
def bags(j2, tmp_path_factory):
    """Write the runs clean and as a machine's recorder writes them."""
    folder = tmp_path_factory.mktemp('stamps')
    written = {'clean': [], 'machine': []}
    for seed, (name, program) in enumerate(runs(j2).items()):
        recording = asynchronous_commands(program_of_samples(program, DT), program.size, DT,
                                          command_period=0.02, seed=seed)
        y = simulate(j2, recording.applied, DT, 0.0, v_before=0.0) + \
            np.random.default_rng(seed).normal(0.0, NOISE, program.size)
        t = DT * np.arange(1, program.size + 1)
        written['clean'].append(str(write_bag(folder / 'clean' / name,
                                              [Record(t, recording.applied, y, 'j2')])))
        written['machine'].append(str(write_recorded_bag(folder / 'machine' / name, recording,
                                                         'j2', y)))
    return written


@pytest.fixture(scope='module')
def identified(bags):
    return {kind: identify(read_records(paths[:1], None, None)) for kind, paths in bags.items()}


def test_the_machines_bag_is_stamped_since_1970_and_read_from_its_start(bags):
    data = read_bag(bags['machine'][0])
    # The first command came a little before the first sample, in the second before.
    assert EPOCH - 2 * 10 ** 9 <= data.start < EPOCH and data.t[0] < 2.0
    record = data.record()
    assert record.sample_period == 0.01
    clean = read_bag(bags['clean'][0]).record()
    # Commands received within the jitter of a sample may pair with its neighbour: a few.
    assert np.mean(record.v[-len(clean):] != clean.v[-len(record):]) < 0.03


def test_identify_is_unchanged(identified):
    clean, machine = identified['clean'], identified['machine']
    assert machine.sample_period == clean.sample_period == 0.01
    assert machine.model.delay == clean.model.delay == 0.15
    assert repr(machine.model.delay) == '0.15'
    assert machine.model.effects == clean.model.effects == ()
    for key in ('dead_zone', 'saturation_velocity', 'curvature'):
        np.testing.assert_allclose(getattr(machine.model.static_map, key),
                                   getattr(clean.model.static_map, key), rtol=0.01)


def test_evaluate_and_diagnose_are_unchanged(bags, identified):
    model = identified['clean'].model
    scores = {}
    for kind, paths in bags.items():
        records = read_records(paths[1:], None, None)
        scores[kind] = np.mean([s.model for s in evaluate(records, model)])
    assert scores['machine'] == pytest.approx(scores['clean'], rel=0.1, abs=0.005)
    found = {kind: diagnose(read_records(paths, None, None), model, max_iterations=1).effect
             for kind, paths in bags.items()}
    assert found['machine'] == found['clean']


def test_calibrate_is_unchanged(bags):
    # The command's pipeline on the bags as the command reads them (its report and files,
    # drawn and written from the result, see no stamp: test_calibrate covers them).
    results = {kind: calibrate(read_records(paths[:2], None, None),
                               read_records(paths[2:], None, None),
                               CalibrationSettings(input_limits=(-10.0, 10.0)))
               for kind, paths in bags.items()}
    for kind, result in results.items():
        assert result.check.passed, kind
        assert result.model.delay == 0.15
    assert results['machine'].effects == results['clean'].effects == ()
    assert results['machine'].mae_final == pytest.approx(results['clean'].mae_final, rel=0.2,
                                                         abs=0.01)


def test_a_joint_that_sits_at_its_stop_gets_no_effect(j2, tmp_path):
    # Steps growing until the joint drives into its stops and sits there for a moment
    # (too short to be cut as a clamp): no stroke factor, the saturation speeds right.
    program = np.concatenate([np.zeros(200)] + [
        np.r_[np.full(300, sign * level), np.zeros(200)]
        for level in (1.5, 2.0, 2.5, 3.0, 4.0, 6.0, 8.0) for sign in (1.0, -1.0)])
    recording = asynchronous_commands(program_of_samples(program, DT), program.size, DT, seed=9)
    y = simulate(j2, recording.applied, DT, 0.0, v_before=0.0) + \
        np.random.default_rng(9).normal(0.0, NOISE, program.size)
    assert np.sum(y < j2.angle_limits[0] + 0.1) > 30      # sat at the lower stop
    bag = write_recorded_bag(tmp_path / 'stops', recording, 'j2', y)
    result = identify(read_records([str(bag)], None, None))
    assert result.model.effects == ()
    np.testing.assert_allclose(result.model.static_map.saturation_velocity,
                               j2.static_map.saturation_velocity, rtol=0.01)

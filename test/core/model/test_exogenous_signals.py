"""Signals beyond a joint's own: Record load/others, flow_sharing and load_dependence."""

from dataclasses import replace
import math
from pathlib import Path
from typing import Any, Sequence, TypeVar

from hydro_sdp.bags import read_bag, write_bag
from hydro_sdp.core.diagnosis.context import Context
from hydro_sdp.core.diagnosis.detectors import detector, VOCABULARY
from hydro_sdp.core.diagnosis.detectors.base import feature_signature
from hydro_sdp.core.diagnosis.detectors.overrun import fit_overrun
from hydro_sdp.core.diagnosis.detectors.record_scales import block_scale
from hydro_sdp.core.diagnosis.residuals import runs_of
from hydro_sdp.core.errors import DataError, ModelFileError, TopicNotFoundError
from hydro_sdp.core.model.effects import FlowSharing, LoadDependence
from hydro_sdp.core.model.exogenous_signals import (
    Exogenous, exogenous_factor, exogenous_of, load_factor, record_key, smoothed_speeds)
from hydro_sdp.core.model.joint_model import JointModel
from hydro_sdp.core.model.records import Record
from hydro_sdp.core.model.simulation import JointSimulator, simulate
from hydro_sdp.core.model.static_maps import SdpDzMap
import numpy as np
import pytest

DT = 0.01
T = TypeVar('T')


def given(value: T | None) -> T:
    """Return ``value``, which the test expects to be there."""
    assert value is not None
    return value


def load_effect(model: JointModel) -> LoadDependence:
    """Return the model's load_dependence effect."""
    effect = model.effect('load_dependence')
    assert isinstance(effect, LoadDependence)
    return effect


def linear_model(**changes: Any) -> JointModel:
    model = JointModel('arm', SdpDzMap(dead_zone=(-0.5, 0.5), slope=(10.0, 10.0)), delay=0.05)
    return replace(model, **changes)


def test_record_carries_load_and_others_and_checks_them() -> None:
    t = DT * np.arange(1, 11)
    record = Record(t, np.ones(10), np.zeros(10), 'arm', 'bag', load=np.arange(10.0),
                    others=np.arange(10.0), other_joints=('boom',))
    assert given(record.others).shape == (10, 1) and record.other_joints == ('boom',)
    piece = record.window(2, 5)
    assert given(piece.load).tolist() == [2.0, 3.0, 4.0]
    assert given(piece.others)[:, 0].tolist() == [2, 3, 4]
    assert piece.other_joints == ('boom',)
    with pytest.raises(DataError, match='load must have one value per sample'):
        Record(t, np.ones(10), np.zeros(10), load=np.ones(9))
    with pytest.raises(DataError, match='others has 2 columns but 1 other_joints'):
        Record(t, np.ones(10), np.zeros(10), others=np.ones((10, 2)), other_joints=('boom',))
    with pytest.raises(DataError, match='other_joints named without others'):
        Record(t, np.ones(10), np.zeros(10), other_joints=('boom',))
    bad = np.ones(10)
    bad[3] = np.nan
    with pytest.raises(DataError, match='1 load samples are NaN or infinite .first at sample 3'):
        Record(t, np.ones(10), np.zeros(10), load=bad)
    with pytest.raises(DataError, match='other-joint angle samples are NaN'):
        Record(t, np.ones(10), np.zeros(10), others=bad)


def test_smoothed_speeds_of_a_ramp_and_the_record_key() -> None:
    angles = np.c_[np.arange(50) * 0.2, np.zeros(50)]
    speeds = smoothed_speeds(angles, DT)
    assert speeds[0].tolist() == [0.0, 0.0]
    np.testing.assert_allclose(speeds[1:, 0], 20.0)
    np.testing.assert_allclose(speeds[:, 1], 0.0)
    # A sample missing from the recording: with the stamps the speed stays 20 deg/s.
    stamps = DT * np.delete(np.arange(51), 30)
    ramp = 20.0 * stamps[:, None]
    np.testing.assert_allclose(smoothed_speeds(ramp, DT, stamps)[1:, 0], 20.0)
    assert smoothed_speeds(ramp, DT)[35, 0] > 21.0
    record = Record(DT * np.arange(1, 51), np.zeros(50), np.zeros(50), 'arm', 'run 1',
                    origin=0.0, others=angles)
    assert record_key(record) == 'run 1 arm at 0.010 s'
    # The bag's folder name, however its path was typed.
    for typed in ('bags/run 1', './bags/../bags/run 1/', '/data/bags/run 1'):
        assert record_key(replace(record, source=typed)) == 'run 1 arm at 0.010 s'
    exogenous = exogenous_of(record)
    assert exogenous.load is None and exogenous.key == 'run 1 arm at 0.010 s'
    np.testing.assert_allclose(given(exogenous.other_speeds)[10:, 0], 20.0)


def test_flow_sharing_factor_is_the_pumps_share() -> None:
    sharing = FlowSharing(limit=1.2, full_positive=20.0, full_negative=10.0,
                          other_positive=30.0, other_negative=60.0)
    model = linear_model(effects=(sharing,))
    speed = np.array([20.0, -10.0, 10.0, 20.0, 0.0])
    others = np.array([[0.0], [30.0], [-60.0], [-30.0], [30.0]])
    factor = given(exogenous_factor(model, speed, Exogenous(other_speeds=others)))
    # Demands: 1 + 0, 1 + 1, 0.5 + 1, 1 + 0.5, 0 + 1.
    np.testing.assert_allclose(factor, [1.0, 0.6, 0.8, 0.8, 1.0])
    # Without the others' motion the joint alone keeps its speed (limit >= 1).
    np.testing.assert_allclose(given(exogenous_factor(model, speed)), 1.0)
    assert exogenous_factor(linear_model(), speed) is None


def test_load_dependence_factor_with_a_load_and_per_record() -> None:
    effect = LoadDependence(positive=0.01, negative=-0.002, reference=100.0,
                            records=('a arm at 0.000 s',), record_positive=(1.2,),
                            record_negative=(0.9,))
    model = linear_model(effects=(effect,))
    speed = np.array([5.0, -5.0, 0.0])
    load = Exogenous(load=np.array([150.0, 150.0, 150.0]))
    np.testing.assert_allclose(given(exogenous_factor(model, speed, load)), [1.5, 0.9, 1.0])
    # Far below the reference the factor stops at 0.05, not below zero.
    low = Exogenous(load=np.array([-1000.0, 0.0, 0.0]))
    np.testing.assert_allclose(given(exogenous_factor(model, speed, low))[0], 0.05)
    named = Exogenous(key='a arm at 0.000 s')
    np.testing.assert_allclose(given(exogenous_factor(model, speed, named)), [1.2, 0.9, 1.0])
    np.testing.assert_allclose(given(exogenous_factor(model, speed, Exogenous(key='b'))), 1.0)


def test_an_overrunning_load_factor_grows_as_the_root_of_the_load_beyond_its_onset() -> None:
    # Extending, the load overruns below -10 bar; retracting, above 20 bar.
    effect = LoadDependence(overrun_positive=-0.1, onset_positive=-10.0,
                            overrun_negative=0.05, onset_negative=20.0)
    model = linear_model(effects=(effect,))
    speed = np.array([5.0, 5.0, 5.0, -5.0, -5.0, 0.0])
    load = Exogenous(load=np.array([-90.0, -10.0, 40.0, 80.0, -50.0, -90.0]))
    # sqrt(1 + 0.1 * 80) = 3 and sqrt(1 + 0.05 * 60) = 2; 1 short of the onset and at rest.
    np.testing.assert_allclose(given(exogenous_factor(model, speed, load)),
                               [3.0, 1.0, 1.0, 2.0, 1.0, 1.0])
    np.testing.assert_allclose(load_factor(np.array([-90.0]), 0.01, -40.0, -0.1, -10.0),
                               [0.5 * 3.0])
    data = model.to_mapping()
    assert data['effects']['load_dependence']['onset_negative'] == 20.0
    assert JointModel.from_mapping(data) == model
    with pytest.raises(ModelFileError, match='must be finite'):
        LoadDependence(overrun_positive=math.inf)


def test_fit_overrun_recovers_the_onset_and_the_growth() -> None:
    rng = np.random.default_rng(4)
    load = rng.uniform(-100.0, 100.0, 4000)
    predicted = rng.uniform(0.05, 0.3, load.size)
    # The squared factor grows by 0.05 per unit as the load falls below -20.
    truth = np.sqrt(1.0 + np.maximum(0.0, -0.05 * (load + 20.0)))
    measured = predicted * truth + rng.normal(0.0, 0.002, load.size)
    g, onset = fit_overrun(measured, predicted, load)
    assert g == pytest.approx(-0.05, rel=0.05) and onset == pytest.approx(-20.0, abs=1.5)
    # No load effect: nothing beats the factor 1 by more than the noise, or a null fit.
    g, onset = fit_overrun(predicted + rng.normal(0.0, 0.002, load.size), predicted, load)
    factor = np.sqrt(1.0 + np.maximum(0.0, g * (load - onset)))
    assert np.max(factor) < 1.02
    assert fit_overrun(measured, predicted, np.full(load.size, 3.0)) == (0.0, 0.0)


def test_effects_round_trip_through_the_model_file_and_refuse_bad_values() -> None:
    model = linear_model(effects=(
        FlowSharing(1.1, 30.0, 35.0, 20.0, 40.0),
        LoadDependence(records=('run 1 arm at 0.000 s', 'run 2 arm at 0.000 s'),
                       record_positive=(1.0, 1.3), record_negative=(1.0, 0.9))))
    data = model.to_mapping()
    names = data['effects']['load_dependence']['records']
    assert names == ['run 1 arm at 0.000 s', 'run 2 arm at 0.000 s']
    assert JointModel.from_mapping(data) == model
    with pytest.raises(ModelFileError, match="effects.flow_sharing.limit': must be > 0"):
        FlowSharing(0.0, 1.0, 1.0, 1.0, 1.0)
    with pytest.raises(ModelFileError, match='one value per record'):
        LoadDependence(records=('a',), record_positive=(1.0,))
    data['effects']['load_dependence']['records'] = [1, 2]
    with pytest.raises(ModelFileError, match='expected a list of names'):
        JointModel.from_mapping(data)


def test_simulation_applies_the_signals_and_the_step_simulator_agrees_without_them() -> None:
    sharing = FlowSharing(1.0, 10.0, 10.0, 20.0, 20.0)
    model = linear_model(effects=(sharing,))
    v = np.r_[np.zeros(10), np.full(90, 1.5)]
    others = np.zeros((100, 1))
    others[50:, 0] = 20.0    # the other joint moves at 20 deg/s from sample 50 on
    speeds = np.zeros((100, 1))
    speeds[50:] = 20.0
    alone = simulate(model, v, DT, 0.0)
    shared = simulate(model, v, DT, 0.0, exogenous=Exogenous(other_speeds=speeds))
    # 10 deg/s alone; half of that (limit 1 / (1 + 1)) while the other moves.
    np.testing.assert_allclose(np.diff(alone)[60:], 0.1)
    np.testing.assert_allclose(np.diff(shared)[60:], 0.05)
    sim = JointSimulator(model, DT, 0.0, v_before=v[0])
    stepped = [0.0] + [sim.step(c) for c in v[1:]]
    np.testing.assert_allclose(stepped, alone)


def test_detectors_are_not_applicable_without_the_signals() -> None:
    assert {'flow_sharing', 'load_dependence'} <= set(VOCABULARY)
    t = DT * np.arange(1, 601)
    v = np.where((t % 2.0) < 1.0, 1.5, -1.5)
    y = simulate(linear_model(), v, DT, 0.0)
    record = Record(t, v, y, 'arm', 'one')
    context = Context(linear_model(), runs_of([record], 0.5), 50)
    for word in ('flow_sharing', 'load_dependence'):
        candidate, augmented = detector(word).fit(context)
        assert not candidate.applicable and augmented is None
        assert candidate.evidence
    assert 'no other joints' in detector('flow_sharing').fit(context)[0].evidence
    still = replace(record, others=np.zeros((600, 1)), other_joints=('boom',))
    context = Context(linear_model(), runs_of([still], 0.5), 50)
    assert 'never move' in detector('flow_sharing').fit(context)[0].evidence
    signature = feature_signature('flow_sharing', 'others', linear_model(), linear_model(),
                                  context.runs[0])
    assert signature.x is not None and signature.x.size == signature.before.size


def test_block_scale_and_its_error() -> None:
    predicted = np.tile([1.0, 1.0, 0.0, 2.0], 50)
    scale, error = block_scale(1.25 * predicted, predicted, 10)
    assert scale == pytest.approx(1.25) and error < 1e-9
    noise = np.random.default_rng(0).normal(0.0, 0.1, predicted.size)
    scale, error = block_scale(predicted + noise, predicted, 10)
    assert abs(scale - 1.0) < 4 * error and 0.001 < error < 0.05
    assert math.isnan(block_scale(np.zeros(5), np.zeros(5), 10)[0])


def test_a_bag_gives_the_other_joints_and_the_held_load(tmp_path: Path) -> None:
    t = DT * np.arange(1, 201)
    arm = Record(t, np.full(200, 0.5), np.linspace(0.0, 10.0, 200), 'arm')
    boom = Record(t, np.zeros(200), np.linspace(5.0, -5.0, 200), 'boom')
    pressure = 100.0 + np.arange(200.0)
    # write_bag stores setpoints in radians: degrees in, so the topic holds the pressure.
    path = write_bag(tmp_path / 'two', [arm, boom], setpoints={'arm_load': np.degrees(pressure)})
    data = read_bag(path)
    plain = data.record('arm')
    assert plain.others is None and plain.load is None
    record = data.record('arm', load_topic='/arm_load/setpoint', others=True)
    assert record.other_joints == ('boom',)
    # Held like a command: the value in force at a sample is the last one stamped before
    # it, so the load stamped with each sample counts from the next one on, and the
    # first sample, with no load before it, is dropped.
    assert len(record) == 199
    np.testing.assert_allclose(given(record.load), pressure[:-1], atol=1e-9)
    np.testing.assert_allclose(given(record.others)[:, 0], boom.y[1:], atol=1e-9)
    np.testing.assert_allclose(record.y, arm.y[1:], atol=1e-9)
    with pytest.raises(TopicNotFoundError, match='no .* load topic /missing'):
        data.record('arm', load_topic='/missing')


def test_a_joint_the_publisher_cannot_measure_is_left_out_of_the_others(tmp_path: Path) -> None:
    # JointState publishers send NaN for a joint they cannot measure: that joint is not
    # one of the others, and the record reads as without it.
    t = DT * np.arange(1, 201)
    arm = Record(t, np.full(200, 0.5), np.linspace(0.0, 10.0, 200), 'arm')
    boom = Record(t, np.zeros(200), np.linspace(5.0, -5.0, 200), 'boom')
    bucket = Record(t, np.zeros(200), np.zeros(200), 'bucket')
    data = read_bag(write_bag(tmp_path / 'three', [arm, boom, bucket]))
    data.positions[50, data.names.index('bucket')] = np.nan
    record = data.record('arm', others=True)
    assert record.other_joints == ('boom',)
    np.testing.assert_allclose(given(record.others)[:, 0], boom.y[-len(record):], atol=1e-9)


def loaded_records(effect: LoadDependence, loads: Sequence[float],
                   seed: int = 0) -> list[Record]:
    """Random levels of the linear joint, each record at one measured load, effect hidden."""
    rng = np.random.default_rng(seed)
    records = []
    for i, load in enumerate(loads):
        held = rng.choice([-2.0, -1.5, -1.0, 1.0, 1.5, 2.0], size=40)
        v = np.r_[np.zeros(100), np.repeat(held, 150)]
        signal = np.full(v.size, float(load))
        y = simulate(linear_model(effects=(effect,)), v, DT, 0.0,
                     exogenous=Exogenous(load=signal))
        y = y + rng.normal(0.0, 0.002, y.size)
        records.append(Record(DT * np.arange(1, v.size + 1), v, y, 'arm', f'run {i}',
                              load=signal))
    return records


def test_load_dependence_is_fitted_on_a_measured_load() -> None:
    from hydro_sdp.core.diagnosis import diagnose
    hidden = LoadDependence(positive=0.004, negative=-0.002, reference=50.0)
    records = loaded_records(hidden, (50.0, 150.0, 50.0, 150.0))
    result = diagnose(records[:3], linear_model(), validation=records[3:], max_iterations=1)
    assert result.effect == 'load_dependence'
    assert result.ledger[0].mae_after <= 0.3 * result.ledger[0].mae_before
    found = load_effect(result.model)
    # Speed x1.4 up and x0.8 down at 150 bar against the reference: the smooth factor of
    # the load per direction recovers both.
    up, down = (found.smooth_factor(np.array([50.0, 150.0]), positive) for positive in
                (True, False))
    assert up[1] / up[0] == pytest.approx(1.4, abs=0.03)
    assert down[1] / down[0] == pytest.approx(0.8, abs=0.03)
    assert up[0] == pytest.approx(1.0, abs=0.03)
    # With the load at one value everywhere the effect cannot be told apart.
    same = loaded_records(hidden, (50.0, 50.0))
    candidate = next(c for c in diagnose(same, linear_model(), max_iterations=1).candidates
                     if c.effect == 'load_dependence')
    assert not candidate.significant and 'does not change' in candidate.evidence


def test_diagnose_command_reads_the_other_joints_and_the_load_topic(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    import json

    from hydro_sdp.cli.main import main
    from hydro_sdp.io.model_files import save_model
    hidden = FlowSharing(1.0, 20.0, 20.0, 20.0, 20.0)
    rng = np.random.default_rng(3)
    bags = []
    for i in range(2):
        v = np.r_[np.zeros(100), np.repeat(rng.choice([-2.0, -1.5, 1.5, 2.0], size=30), 150)]
        t = DT * np.arange(1, v.size + 1)
        # The boom swings at 20 deg/s for 2 s out of every 4.
        boom_speed = np.where((t % 4.0) < 2.0, 20.0, 0.0) * np.where((t % 8.0) < 4.0, 1.0, -1.0)
        boom_y = np.cumsum(boom_speed) * DT
        speeds = smoothed_speeds(boom_y[:, None], DT)
        y = simulate(linear_model(effects=(hidden,)), v, DT, 0.0,
                     exogenous=Exogenous(other_speeds=speeds))
        arm = Record(t, v, y, 'arm')
        boom = Record(t, np.zeros(v.size), boom_y, 'boom')
        bags.append(str(write_bag(tmp_path / f'run{i}', [arm, boom],
                                  setpoints={'arm_load': np.full(v.size, np.degrees(80.0))})))
    save_model(linear_model(), tmp_path / 'arm.yaml')
    code = main(['diagnose', *bags, '--model', str(tmp_path / 'arm.yaml'), '--iterations', '1',
                 '--load-topic', '/arm_load/setpoint', '--json'])
    out = capsys.readouterr().out
    assert code == 0
    result = json.loads(out)
    assert result['effect'] == 'flow_sharing'
    assert result['ledger'][0]['mae_after'] < 0.3 * result['ledger'][0]['mae_before']
    load = next(c for c in result['candidates'] if c['effect'] == 'load_dependence')
    assert load['applicable'] and 'does not change' in load['evidence']
    sharing = result['model']['effects']['flow_sharing']
    # The joint's own full demand is the model's top speed at the commands recorded; only
    # limit x full speed and limit x other speed matter: 20 deg/s each, as hidden.
    assert sharing['full_positive'] == pytest.approx(linear_model().rate(np.array([2.0]))[0])
    for key in ('full_positive', 'full_negative', 'other_positive', 'other_negative'):
        assert sharing['limit'] * sharing[key] == pytest.approx(20.0, rel=0.1)
    with pytest.raises(SystemExit):
        main(['diagnose', '--help'])
    assert '--load-topic' in capsys.readouterr().out
    # evaluate reads the other joints too: the true model's error is the noise-free 0, and
    # the model without the effect keeps its error.
    save_model(linear_model(effects=(hidden,)), tmp_path / 'true.yaml')
    errors = {}
    for name in ('true', 'arm'):
        assert main(['evaluate', *bags, '--model', str(tmp_path / f'{name}.yaml'),
                     '--json']) == 0
        errors[name] = json.loads(capsys.readouterr().out)['mae']['model']
    assert errors['true'] < 1e-6 < 0.3 * errors['arm']

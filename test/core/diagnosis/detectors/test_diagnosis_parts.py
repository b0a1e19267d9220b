"""The parts of the discrepancy workflow: one detector registry, runs, signatures, evidence."""

from dataclasses import replace

from conftest import REPO
from hydro_sdp.core.diagnosis import (
    detector, DETECTORS, diagnose, runs_of, velocity_residuals, VOCABULARY)
from hydro_sdp.core.diagnosis.detectors import vocabulary_table
from hydro_sdp.core.diagnosis.detectors.base import FEATURE_LABELS, feature_signature
from hydro_sdp.core.errors import ConfigurationError
from hydro_sdp.core.identification.evaluation import evaluate, mean_errors, simulated_angles
from hydro_sdp.core.model.effects import Backlash, ValveLag
from hydro_sdp.core.model.records import Record
from hydro_sdp.core.model.simulation import simulate
from hydro_sdp.core.synthetic.joint_experiments import experiment_record
import numpy as np
import pytest


def stepped_record(model, levels, hold, dt=0.01, y0=20.0):
    """Return a noiseless record of ``model`` driven by ``levels`` held ``hold`` samples each."""
    v = np.repeat(np.asarray(levels, dtype=float), hold)
    y = simulate(model, v, dt, y0)
    return Record(np.arange(1, v.size + 1) * dt, v, y, joint=model.joint)


def test_the_vocabulary_is_the_registry_in_search_order():
    assert VOCABULARY == ('dead_zone', 'velocity_saturation', 'asymmetry', 'time_delay',
                          'direction_dependent_delay', 'angle_limits', 'valve_lag', 'backlash',
                          'angle_dependent_velocity', 'stroke_geometry', 'flow_sharing',
                          'load_dependence', 'oscillation')
    assert tuple(d.word for d in DETECTORS) == VOCABULARY
    features = {d.word: d.feature for d in DETECTORS}
    assert features == {
        'dead_zone': 'command', 'velocity_saturation': 'command', 'asymmetry': 'command',
        'time_delay': 'events', 'direction_dependent_delay': 'events', 'valve_lag': 'events',
        'backlash': 'reversals', 'angle_limits': 'angle', 'angle_dependent_velocity': 'angle',
        'stroke_geometry': 'angle', 'flow_sharing': 'others', 'load_dependence': 'command',
        'oscillation': 'events'}
    for each in DETECTORS:
        assert detector(each.word) is each
        assert each.description and each.remedy and each.feature in FEATURE_LABELS
    with pytest.raises(ConfigurationError, match="unknown effect 'gravity'"):
        detector('gravity')


def test_the_guide_table_is_the_registry():
    guide = (REPO / 'docs' / 'guide' / 'diagnosis.md').read_text().splitlines()
    header = guide.index('| word | what the model misses | how it is added |')
    rows = guide[header:header + 2 + len(DETECTORS)]
    assert rows == vocabulary_table()
    interfaces = (REPO / 'docs' / 'interfaces.md').read_text()
    section = interfaces[interfaces.index('## 5. Discrepancy vocabulary'):].split('\n---')[0]
    words = [line.split('`')[1] for line in section.splitlines() if line.startswith('| `')]
    assert words[:len(VOCABULARY)] == list(VOCABULARY) and words[-1] == 'none'


def test_a_run_starts_once_the_command_has_been_held(j2):
    # Holds of 30, 150 and 100 samples: the first longer than 1 s (100 samples) starts at 30.
    v = np.r_[np.full(30, 1.0), np.full(150, 2.0), np.full(100, 3.0)]
    held = Record(np.arange(1, v.size + 1) * 0.01, v, np.zeros(v.size), joint=j2.joint)
    assert runs_of([held], 0.5)[0].start == 130
    # No hold long enough: the largest delay plus one sample.
    v = np.tile(np.r_[np.full(50, 1.0), np.full(50, -1.0)], 3)
    short = Record(np.arange(1, v.size + 1) * 0.01, v, np.zeros(v.size), joint=j2.joint)
    run, = runs_of([short], 0.5)
    assert (run.start, run.dt) == (51, pytest.approx(0.01))


def test_event_signature_marks_the_delayed_command_changes(j2):
    # Commands change at samples 150 and 300; the model's delay shifts them by tau.
    record = stepped_record(j2, [0.0, 2.5, -2.5, -2.5], 150)
    run, = runs_of([record], 0.5)
    tau = j2.delay_samples(0.01)
    lagged = j2.with_effect(ValveLag(0.1))
    signature = feature_signature('valve_lag', 'events', j2, lagged, run)
    # Residual i is the increment into sample start + 1 + i.
    first, second = 150 + tau - run.start - 1, 300 + tau - run.start - 1
    assert run.start == 100
    assert signature.triggers.tolist() == [first, second]
    assert signature.signs.tolist() == [1.0, -1.0]
    assert signature.x is None and signature.label == FEATURE_LABELS['events']
    assert np.array_equal(signature.before, velocity_residuals(j2, [run])[0])
    assert np.array_equal(signature.after, velocity_residuals(lagged, [run])[0])
    # The model that made the data leaves no residual; the lagged one does, after changes.
    assert np.max(np.abs(signature.before)) < 1e-9
    assert np.max(np.abs(signature.after[first:first + 20])) > 1e-3


def test_binned_and_reversal_signatures_hold_their_feature(j2):
    record = stepped_record(j2, [0.0, 2.5, -2.5, 3.0, 0.0], 150)
    run, = runs_of([record], 0.5)
    tau = j2.delay_samples(0.01)
    angle = feature_signature('angle_limits', 'angle', j2, j2, run)
    assert np.array_equal(angle.x, record.y[run.start:-1])
    command = feature_signature('dead_zone', 'command', j2, j2, run)
    assert np.array_equal(command.x, record.v[np.arange(run.start + 1, len(record)) - tau])
    assert command.x.size == angle.x.size == command.before.size
    # Motion reverses twice: when -2.5 and when 3.0 take effect (the rest at 0 only stops it).
    reversals = feature_signature('backlash', 'reversals', j2,
                                  j2.with_effect(Backlash(1.0)), run)
    assert reversals.triggers.tolist() == [300 + tau - run.start - 1, 450 + tau - run.start - 1]
    assert reversals.signs.tolist() == [-1.0, 1.0]


def test_the_diagnosis_carries_its_evidence(j2):
    truth = j2.with_effect(ValveLag(0.15))
    records = [experiment_record(truth, 'random', seed=seed, duration=40.0) for seed in (3, 4)]
    untouched = diagnose(records[:1], j2, validation=records[1:], max_iterations=0)
    gap = untouched.gap
    assert untouched.effect == 'none' and untouched.signature is None
    # The gap drawn is the simulation whose error every command reports (evaluate's).
    start = j2.delay_samples(0.01)
    assert np.array_equal(gap.t, records[1].t[start:])
    assert np.array_equal(gap.measured, records[1].y[start:])
    assert np.array_equal(gap.before, simulated_angles(j2, records[1])[start:])
    assert np.array_equal(gap.after, gap.before)
    assert untouched.mae_before == pytest.approx(np.mean(np.abs(gap.measured - gap.before)))
    assert untouched.mae_before == pytest.approx(
        mean_errors(evaluate(records[1:], j2))['per_record']['model'], abs=1e-12)
    result = diagnose(records[:1], j2, validation=records[1:], max_iterations=1)
    assert result.effect == 'valve_lag'
    signature = result.signature
    assert signature is not None and signature.feature == 'events'
    estimation, = runs_of(records[:1], 0.5)
    assert np.array_equal(signature.after, velocity_residuals(result.model, [estimation])[0])
    # Compared from where both models' states are known: the lag's, 5 time constants later.
    lag = result.model.effect('valve_lag').time_constant
    later = start + int(np.ceil(5.0 * lag / 0.01))
    assert np.array_equal(result.gap.t, records[1].t[later:])
    assert np.array_equal(result.gap.after, simulated_angles(result.model, records[1])[later:])
    assert np.mean(np.abs(result.gap.measured - result.gap.after)) < \
        0.5 * np.mean(np.abs(result.gap.measured - result.gap.before))


def test_signatures_of_several_runs_join_with_their_events_shifted():
    from hydro_sdp.core.diagnosis.results import Signature
    first = Signature('valve_lag', 'events', 'x', 0.01, np.zeros(5), np.ones(5), None,
                      np.array([1, 3]), np.array([1.0, -1.0]))
    second = Signature('valve_lag', 'events', 'x', 0.01, np.zeros(4), np.ones(4), None,
                       np.array([0, 2]), np.array([-1.0, 1.0]))
    joined = Signature.joined([first, second])
    assert joined.before.size == joined.after.size == 9 and joined.x is None
    assert joined.triggers.tolist() == [1, 3, 5, 7]
    assert joined.signs.tolist() == [1.0, -1.0, -1.0, 1.0]
    assert [joined.part_end(k) for k in (0, 4, 5, 8)] == [5, 5, 9, 9]
    assert first.part_end(2) == 5
    # An event's window never runs into the next run: 3 and 7 are too close to their end.
    from hydro_sdp.plots.diagnosis import _event_average
    values = np.arange(9.0)
    lags, mean = _event_average(joined, values, 3)
    np.testing.assert_allclose(mean, np.mean([values[1:4], -values[5:8]], axis=0))
    angle = Signature('stroke_geometry', 'angle', 'x', 0.01, np.zeros(2), np.ones(2),
                      np.array([10.0, 11.0]), np.zeros(0, dtype=np.int64), np.array([1.0, 1.0]))
    both = Signature.joined([angle, replace(angle, x=np.array([30.0, 29.0]),
                                            signs=np.array([-1.0, -1.0]))])
    assert both.x.tolist() == [10.0, 11.0, 30.0, 29.0]
    assert both.signs.tolist() == [1.0, 1.0, -1.0, -1.0]

"""One simulation error: evaluate, diagnose and calibrate report the same figure."""

from dataclasses import replace

from hydro_sdp.core.diagnosis import diagnose
from hydro_sdp.core.identification.evaluation import evaluate, mean_errors, record_mae
from hydro_sdp.core.model.effects import Backlash, ValveLag
from hydro_sdp.core.model.records import Record
from hydro_sdp.core.model.simulation import simulate
import numpy as np
import pytest

DT = 0.01


def _records(truth, rng, count=2, noise=0.02):
    """Random levels that start away from rest (the command held before the record)."""
    records = []
    for index in range(count):
        levels = rng.choice([-4.0, -2.5, 2.5, 4.0], size=12)
        v = np.repeat(levels, 150)
        # Moving before the record began: any play is taken up against the motion.
        play = truth.effect(Backlash.name)
        offset = -0.5 * play.play * np.sign(v[0]) if isinstance(play, Backlash) else 0.0
        y = simulate(truth, v, DT, 20.0, v_before=float(v[0]), backlash_offset=offset)
        y = y + rng.normal(0.0, noise, v.size)
        records.append(Record(DT * np.arange(1, v.size + 1), v, y, 'j2', source=f'run{index}'))
    return records


@pytest.mark.parametrize('effect', [ValveLag(0.12), Backlash(1.0)], ids=['lag', 'backlash'])
def test_diagnose_and_evaluate_report_the_same_mae(j2, rng, effect):
    truth = j2.with_effect(effect)
    records = _records(truth, rng)
    wrong = replace(j2, delay=0.12)
    result = diagnose(records, wrong, max_iterations=1)
    evaluated = mean_errors(evaluate(records, wrong))['per_record']['model']
    assert result.ledger[0].mae_before == pytest.approx(evaluated, abs=1e-9)
    assert result.ledger[0].mae_after == pytest.approx(
        np.mean([record_mae(result.model, record) for record in records]), abs=1e-9)


@pytest.mark.parametrize('effect', [ValveLag(0.12), Backlash(1.0)], ids=['lag', 'backlash'])
def test_the_true_model_has_no_error_on_noise_free_records(j2, rng, effect):
    truth = j2.with_effect(effect)
    errors = [record_mae(truth, record) for record in _records(truth, rng, noise=0.0)]
    assert max(errors) < 1e-9
    assert min(record_mae(j2, record) for record in _records(truth, rng, noise=0.0)) > 0.01

"""The diagnosis corrects a valve lag that the model has but with a wrong time constant."""

from dataclasses import replace

from hydro_sdp.core.diagnosis import diagnose
from hydro_sdp.core.model.effects import ValveLag
from hydro_sdp.core.model.joint_model import JointModel
from hydro_sdp.core.model.records import Record
import numpy as np
import pytest
from support.diagnosis_grid import hide, records_of


@pytest.fixture(scope='module')
def lagged() -> tuple[JointModel, list[Record]]:
    """Return a generator joint with a 0.15 s lag: one 40 s record to fit, one to judge."""
    rng = np.random.default_rng(4)
    truth, _ = hide('valve_lag', rng, 'volt')
    truth = replace(truth, joint=replace(truth.joint, lag=0.15))
    base = JointModel.from_mapping({**truth.mapping, 'effects': {}})
    return base, records_of(truth, 'random', rng, seconds=40.0, count=2)


def test_a_lag_far_too_short_is_named_and_refitted(lagged) -> None:
    base, records = lagged
    result = diagnose(records[:1], base.with_effect(ValveLag(0.03)), validation=records[1:],
                      max_iterations=1)
    assert result.effect == 'valve_lag'
    step, = result.ledger
    assert step.parameters['time_constant'] == pytest.approx(0.15, rel=0.15)
    assert '0.03 s' in next(c.evidence for c in result.candidates if c.effect == 'valve_lag')
    # The gap between the measured and the simulated angle shrinks.
    assert result.mae_after < 0.5 * result.mae_before


def test_the_right_lag_is_not_named(lagged) -> None:
    base, records = lagged
    result = diagnose(records[:1], base.with_effect(ValveLag(0.15)), validation=records[1:],
                      max_iterations=1)
    assert result.effect == 'none' and not result.ledger
    candidate = next(c for c in result.candidates if c.effect == 'valve_lag')
    # Refitted and judged, and found no better than the model's own lag.
    assert candidate.applicable and not candidate.accepted
    assert candidate.parameters['time_constant'] == pytest.approx(0.15, rel=0.15)

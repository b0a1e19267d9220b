"""
Cases the diagnosis once got wrong, on data no test of the detectors was built from.

A stop met for two seconds of a minute (the block sign test found it "not significant"
and answered ``none``); a linear model of a joint with a wide dead-zone and a speed
that levels off (``none``); a resisting load with its pressure logged on a pump whose
power binds, its valve without compensation (the physics plant; ``none``). The records
come from the independent generator and the physics plant (test/support/failure_cases.py).

"""

from dataclasses import replace

from hydro_sdp.core.diagnosis import diagnose, Diagnosis
from hydro_sdp.core.model.effects import LoadDependence
import numpy as np
import pytest
from support.failure_cases import (
    Case, dead_zone_linear, rare_stop, resisting_load, STOPPED, WIDE)


@pytest.fixture(scope='module')
def stop() -> tuple[Case, Diagnosis]:
    case = rare_stop()
    return case, diagnose(case.estimation, case.model, validation=case.validation,
                          max_iterations=2)


def test_a_stop_met_for_two_seconds_is_named_and_the_gap_halves(stop):
    case, result = stop
    assert case.model.angle_limits is None
    contact = np.sum(case.estimation[0].y > STOPPED.stops[1] - 0.1) * 0.01
    assert 1.5 < contact < 2.5
    assert result.effect == 'angle_limits'
    first = result.ledger[0]
    assert first.mae_after <= 0.5 * first.mae_before
    candidate = result.candidates[0]
    assert candidate.effect == 'angle_limits' and candidate.accepted
    assert candidate.signature_match and candidate.p_value <= 0.01
    # The top stop where the joint is held; no stop made up near the lowest angle the
    # joint merely turned at (-28 deg): the side without contact lies beyond the data.
    low, high = result.model.angle_limits
    assert high == pytest.approx(STOPPED.stops[1], abs=0.1)
    assert low < min(r.y.min() for r in case.estimation) - 50.0
    assert '-2' not in candidate.evidence.split('held still at')[1].split('while')[0]


def test_a_model_with_its_stops_gets_none(stop):
    case, _ = stop
    stopped = replace(case.model, angle_limits=STOPPED.stops)
    result = diagnose(case.estimation, stopped, validation=case.validation, max_iterations=1)
    assert result.effect == 'none' and not result.ledger
    assert result.mae_after == result.mae_before < 0.05


def test_a_linear_model_of_a_dead_zone_joint_gets_the_dead_zone_first():
    case = dead_zone_linear(seconds=40.0)
    result = diagnose(case.estimation, case.model, validation=case.validation,
                      max_iterations=1)
    assert result.effect == 'dead_zone', [(c.effect, c.held_out) for c in result.candidates]
    low, high = result.model.dead_zone
    assert low == pytest.approx(WIDE.speed_map.dead_zone[0], abs=0.15)
    assert high == pytest.approx(WIDE.speed_map.dead_zone[1], abs=0.15)
    # The data named the command: the map's words.
    assert result.shares['command'] == max(result.shares.values())
    # The candidates that do not pass say so instead of stating a mismatch.
    for candidate in result.candidates:
        if candidate.applicable and not candidate.accepted and candidate.parameters:
            assert candidate.evidence.startswith(('not significant', 'too small', 'no better'))


@pytest.fixture(scope='module')
def load() -> tuple[Case, Diagnosis]:
    case = resisting_load()
    return case, diagnose(case.estimation, case.model, validation=case.validation,
                          max_iterations=1)


def test_a_resisting_load_with_its_pressure_logged_is_named(load):
    case, result = load
    assert result.effect == 'load_dependence'
    assert result.mae_after <= 0.7 * result.mae_before
    effect = result.model.effect('load_dependence')
    assert isinstance(effect, LoadDependence) and effect.knots
    # Lifting (positive), the heavier the load the slower: the factor falls with the
    # piston pressure over the loads the lifts saw.
    lifts = np.concatenate([r.load[np.diff(r.y, prepend=r.y[0]) > 0.05]
                            for r in case.estimation])
    low, high = np.quantile(lifts, [0.1, 0.9])
    up = effect.smooth_factor(np.array([low, high]), True)
    assert up[1] < 0.9 * up[0]
    # The data named the load: the SDP estimate along it is the report's evidence.
    assert result.evidence is not None and result.evidence.state == 'load'
    assert {e.parameter for e in result.evidence.before} == {'ratio', 'residual'}

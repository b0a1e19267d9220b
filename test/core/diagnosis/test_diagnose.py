"""The discrepancy workflow names effects in turn and rebuilds a model from a linear one."""

from dataclasses import replace

from hydro_sdp.core.diagnosis import diagnose
from hydro_sdp.core.identification.evaluation import evaluate
from hydro_sdp.core.identification.identify import identify
from hydro_sdp.core.model.joint_model import JointModel
from hydro_sdp.core.model.static_maps import LinearMap
import numpy as np
from support.diagnosis_grid import make_case, program
from support.joint_generator import record


def generated(truth_case, joint, seed, seconds=40.0):
    """Return records of ``joint`` (a generator joint) at random levels planned on the case."""
    rng = np.random.default_rng(seed)
    out = []
    for index in range(3):
        v, y0 = program(truth_case.truth.model, 'random', rng, seconds, 0.01)
        out.append(record(replace(truth_case.truth.machine, joints=(joint,)), v[:, None],
                          angles0=[y0], seed=seed + index, source=f'run {seed} {index}'))
    return out


def test_two_effects_are_named_in_turn():
    case = make_case('valve_lag', 'random', 'volt', 3)
    # The joint has a 0.2 s lag and 2 deg of play; the model has neither.
    joint = replace(case.truth.joint, lag=0.2, play=2.0)
    records = generated(case, joint, 77)
    result = diagnose(records[:2], case.model, validation=records[2:], max_iterations=3)
    steps = [step.effect for step in result.ledger]
    assert sorted(steps[:2]) == ['backlash', 'valve_lag'], steps
    assert result.mae_after <= 0.5 * result.mae_before
    # Each step is what the decision weighed: the windowed error falls each time.
    for step in result.ledger:
        assert step.window_after < step.window_before


def test_first_paper_story_from_a_linear_model():
    # [W18]'s story: a linear model of a joint with a dead-zone and saturation; the
    # diagnosis adds what it lacks, and ends near what identify finds from the data.
    case = make_case('none', 'random', 'volt', 5, seconds=40.0)
    truth = case.truth.model
    linear = JointModel(truth.joint, LinearMap(10.0), truth.delay, truth.angle_limits,
                        truth.input_limits)
    result = diagnose(case.estimation, linear, validation=case.validation)
    assert result.effect == 'dead_zone'
    identified = identify(list(case.estimation), kind='sdp',
                          angle_limits=truth.angle_limits).model
    reference = np.mean([s.model for s in evaluate(case.validation, identified)])
    final = np.mean([s.model for s in evaluate(case.validation, result.model)])
    assert final <= 1.5 * reference + 0.05

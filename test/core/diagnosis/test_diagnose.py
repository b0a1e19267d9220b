"""The discrepancy workflow names each missing effect, adds it and shrinks the gap."""

from dataclasses import replace

from hydro_sdp.core.diagnosis import diagnose
from hydro_sdp.core.model.effects import (
    AngleDependentVelocity, Backlash, DirectionDependentDelay, ValveLag)
from hydro_sdp.core.model.joint_model import JointModel
from hydro_sdp.core.model.records import Record
from hydro_sdp.core.model.simulation import simulate
from hydro_sdp.core.model.static_maps import linearise, LinearMap, SdpMap
from hydro_sdp.core.synthetic.programs import random_program
import numpy as np
import pytest


def random_joint(rng):
    """Return an asymmetric J2-like joint with random parameters."""
    return JointModel(
        'arm', SdpMap(dead_zone=(rng.uniform(-1.6, -0.8), rng.uniform(0.8, 1.6)),
                      saturation_velocity=(-rng.uniform(20.0, 30.0), rng.uniform(32.0, 45.0)),
                      curvature=(rng.uniform(1.0, 1.5), rng.uniform(1.8, 2.5))),
        delay=round(rng.uniform(0.08, 0.2), 2), angle_limits=(-30.0, 80.0),
        input_limits=(-10.0, 10.0))


def wild_program(rng, seconds, dt=0.01):
    """Random levels with no regard for the end stops, so that the joint meets them."""
    levels = rng.uniform(-4.0, 4.0, int(seconds))
    holds = rng.integers(50, 200, levels.size)
    return np.repeat(levels, holds)[:int(seconds / dt)]


def record(model, v, rng, dt=0.01, noise=0.02):
    """Return a noisy record of ``model`` driven by ``v``, starting mid-travel."""
    y0 = 25.0 if model.angle_limits is None else float(np.mean(model.angle_limits))
    y = simulate(model, v, dt, y0) + rng.normal(0.0, noise, v.size)
    return Record(np.arange(1, v.size + 1) * dt, v, y, joint=model.joint)


def symmetric(static_map):
    """Return the map with both sides averaged (the model that misses the asymmetry)."""
    edge = 0.5 * (static_map.dead_zone[1] - static_map.dead_zone[0])
    speed = 0.5 * (static_map.saturation_velocity[1] - static_map.saturation_velocity[0])
    curvature = 0.5 * (static_map.curvature[0] + static_map.curvature[1])
    return SdpMap((-edge, edge), (-speed, speed), (curvature, curvature))


def case(effect, rng):
    """Return (true joint, model that misses ``effect``, program) for one random draw."""
    truth = random_joint(rng)
    if effect == 'dead_zone':
        return truth, replace(truth, static_map=replace(truth.static_map, dead_zone=(0.0, 0.0)))
    if effect == 'velocity_saturation':
        chord = linearise(truth.static_map, -3.0, 3.0)
        return truth, replace(truth, static_map=chord)
    if effect == 'asymmetry':
        return truth, replace(truth, static_map=symmetric(truth.static_map))
    if effect == 'time_delay':
        shift = rng.choice([-1.0, 1.0]) * rng.uniform(0.04, 0.07)
        return truth, replace(truth, delay=round(max(0.01, truth.delay + shift), 2))
    if effect == 'direction_dependent_delay':
        slower = round(truth.delay + rng.uniform(0.05, 0.1), 2)
        split = DirectionDependentDelay(*((truth.delay, slower) if rng.random() < 0.5
                                          else (slower, truth.delay)))
        return truth.with_effect(split), truth
    if effect == 'angle_limits':
        stops = replace(truth, angle_limits=(rng.uniform(-15.0, -5.0), rng.uniform(35.0, 50.0)))
        return stops, replace(stops, angle_limits=None)
    if effect == 'valve_lag':
        return truth.with_effect(ValveLag(rng.uniform(0.08, 0.3))), truth
    if effect == 'backlash':
        return truth.with_effect(Backlash(rng.uniform(1.0, 3.0))), truth
    if effect == 'angle_dependent_velocity':
        return truth.with_effect(AngleDependentVelocity(rng.uniform(0.2, 0.4),
                                                        rng.uniform(0.0, 360.0))), truth
    return truth, truth


EFFECTS = ['dead_zone', 'velocity_saturation', 'asymmetry', 'time_delay',
           'direction_dependent_delay', 'angle_limits', 'valve_lag', 'backlash',
           'angle_dependent_velocity', 'none']


def _data(truth, rng, effect):
    def program(seed):
        if effect == 'angle_limits':
            return wild_program(rng, 60.0)
        return random_program(truth, 0.01, 60.0, seed=seed, y0=float(np.mean(truth.angle_limits)))
    estimation = [record(truth, program(int(rng.integers(1e6))), rng) for _ in range(2)]
    validation = [record(truth, program(int(rng.integers(1e6))), rng)]
    return estimation, validation


@pytest.mark.parametrize('seed', range(5))
@pytest.mark.parametrize('effect', EFFECTS)
def test_the_missing_effect_is_named_and_the_gap_halves(effect, seed):
    rng = np.random.default_rng(1000 * EFFECTS.index(effect) + seed)
    truth, model = case(effect, rng)
    estimation, validation = _data(truth, rng, effect)
    result = diagnose(estimation, model, validation=validation)
    named = [c.effect for c in result.candidates if c.significant]
    assert result.effect == effect, (result.effect, named,
                                     [(c.effect, round(c.gain, 3), round(c.t, 1))
                                      for c in result.candidates])
    if effect != 'none':
        assert result.mae_after <= 0.5 * result.mae_before
        assert result.ledger[0].effect == effect
    else:
        assert not result.ledger and result.mae_after == result.mae_before


def test_two_effects_are_named_in_turn():
    rng = np.random.default_rng(77)
    truth = random_joint(rng).with_effect(ValveLag(0.2)).with_effect(Backlash(2.0))
    model = truth.without_effect('valve_lag').without_effect('backlash')
    estimation, validation = _data(truth, rng, 'two')
    result = diagnose(estimation, model, validation=validation)
    steps = [step.effect for step in result.ledger]
    assert sorted(steps[:2]) == ['backlash', 'valve_lag']
    for step in result.ledger:
        assert step.mae_after < step.mae_before
    assert result.mae_after <= 0.5 * result.mae_before


def test_first_paper_story_from_a_linear_model(j2):
    rng = np.random.default_rng(5)
    truth = replace(random_joint(rng), delay=0.15)
    estimation, validation = _data(truth, rng, 'story')
    linear = JointModel(truth.joint, LinearMap(10.0), truth.delay, truth.angle_limits,
                        truth.input_limits)
    result = diagnose(estimation, linear, validation=validation)
    assert result.effect == 'dead_zone'
    from hydro_sdp.core.identification.identify import identify
    identified = identify(estimation, kind='sdp', angle_limits=truth.angle_limits).model
    from hydro_sdp.core.identification.evaluation import evaluate
    reference = np.mean([s.model for s in evaluate(validation, identified)])
    final = np.mean([s.model for s in evaluate(validation, result.model)])
    assert final <= 1.2 * reference + 0.01

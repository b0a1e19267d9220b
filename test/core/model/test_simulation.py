"""Simulation of joint models: delay, dead-zone, saturation, end stops and effects."""

from dataclasses import replace
import math

from hydro_sdp.core.errors import DataError
from hydro_sdp.core.model.effects import (
    AngleDependentVelocity, Backlash, DirectionDependentDelay, Oscillation, StrokeGeometry,
    ValveLag)
from hydro_sdp.core.model.joint_model import JointModel
from hydro_sdp.core.model.simulation import bounded_cumsum, JointSimulator, simulate
from hydro_sdp.core.model.static_maps import LinearMap
from hypothesis import given, settings
from hypothesis import strategies as st
import numpy as np
import pytest
from support.paper_recursion import paper_recursion


def test_matches_the_papers_recursion_with_end_stops(j2, rng):
    v = np.repeat(rng.uniform(-6.0, 6.0, 300), rng.integers(5, 200, 300))
    y = simulate(j2, v, 0.01, 20.0)
    expected = paper_recursion(j2.alpha(0.01), 15, v, 20.0, -13.8, 63.6)
    np.testing.assert_allclose(y, expected, atol=1e-9, rtol=0)
    assert y.min() == -13.8 and y.max() == 63.6  # the run does reach both stops


def test_clamps_at_end_stops_and_leaves_them_at_once(j2):
    v = np.r_[np.full(400, 5.0), np.full(100, -5.0)]
    y = simulate(j2, v, 0.01, 60.0)
    assert y.max() == 63.6
    assert np.all(y[100:415] == 63.6)
    # The reversal reaches the joint after the delay, and it moves off the stop at once.
    assert y[415] == pytest.approx(63.6 + 0.01 * float(j2.rate(-5.0)))


@pytest.mark.parametrize(('dt', 'tau'), [(0.01, 15), (0.05, 3)])
def test_pure_delay_in_samples(j2, dt, tau):
    v = np.full(40, 3.0)
    y = simulate(j2, v, dt, 0.0)
    # y_k = y_{k-1} + dt rate(v_{k-tau}): the first motion shows at sample tau.
    assert np.all(y[:tau] == 0.0)
    assert y[tau] == pytest.approx(dt * float(j2.rate(3.0)))


def test_dead_zone_does_not_move(j2):
    v = np.linspace(-1.3298, 1.3124, 500)
    assert np.all(simulate(j2, v, 0.01, 5.0) == 5.0)


def test_same_angles_at_any_sample_period(j2, rng):
    # Rates scale with dt and the delay in samples with 1/dt: fine samples 5k-4..5k
    # carrying coarse command k give the coarse trajectory at every fifth sample.
    coarse = np.repeat(rng.uniform(-5.0, 5.0, 60), 10)      # 0.05 s
    fine = np.r_[coarse[0], np.repeat(coarse[1:], 5)]       # 0.01 s, same commands
    y_fine = simulate(j2, fine, 0.01, 25.0, v_before=coarse[0])
    y_coarse = simulate(j2, coarse, 0.05, 25.0, v_before=coarse[0])
    np.testing.assert_allclose(y_coarse, y_fine[::5], atol=1e-9)


EFFECT_SETS = [
    (),
    (ValveLag(0.1),),
    (Backlash(1.0),),
    (AngleDependentVelocity(0.3, 20.0),),
    (DirectionDependentDelay(0.15, 0.2),),
    (ValveLag(0.1), Backlash(0.5), AngleDependentVelocity(0.2, 0.0),
     DirectionDependentDelay(0.1, 0.25)),
    (Oscillation(2.0, 0.1),),
    (ValveLag(0.1), Oscillation(2.5, 0.05), Backlash(0.5), AngleDependentVelocity(0.2, 0.0)),
]


@pytest.mark.parametrize('effects', EFFECT_SETS,
                         ids=lambda effects: '+'.join(e.name for e in effects) or 'none')
def test_stepper_equals_vector_simulation(j2, rng, effects):
    model = JointModel('j2', j2.static_map, j2.delay, j2.angle_limits, effects=effects)
    v = np.repeat(rng.uniform(-5.0, 5.0, 120), 40)
    v[0] = 0.5
    y = simulate(model, v, 0.01, 20.0, v_before=0.5)
    sim = JointSimulator(model, 0.01, 20.0, v_before=0.5)
    stepped = np.array([sim.angle] + [sim.step(x) for x in v[1:]])
    np.testing.assert_allclose(stepped, y, atol=1e-9, rtol=0)


def _speed(y, dt):
    return np.diff(y) / dt


def test_valve_lag_is_first_order(j2):
    model = j2.with_effect(ValveLag(0.2))
    v = np.full(200, 3.0)
    speed = _speed(simulate(model, v, 0.01, 0.0), 0.01)
    target = float(j2.rate(3.0))
    # speed[k-1] is w_k; motion starts at k = 15 and reaches 1 - e^-1 after 0.2 s more.
    assert speed[13] == 0.0
    assert speed[14] == pytest.approx(target * (1 - math.exp(-0.01 / 0.2)), rel=1e-9)
    assert speed[14 + 20] == pytest.approx(target * (1 - math.exp(-21 * 0.01 / 0.2)), rel=1e-9)


def test_backlash_holds_the_angle_after_a_reversal():
    model = JointModel('j', LinearMap(10.0), 0.0, effects=(Backlash(2.0),))
    v = np.r_[np.full(100, 1.0), np.full(100, -1.0)]
    y = simulate(model, v, 0.01, 0.0)
    actuator = simulate(JointModel('j', LinearMap(10.0), 0.0), v, 0.01, 0.0)
    # The actuator turns at sample 101; at 10 deg/s the 2 deg play takes 20 samples.
    assert actuator[100] > actuator[101]
    assert np.all(y[100:121] == y[100])
    assert y[122] < y[121]
    # Moving up the sensor trails the actuator by half the play, moving down it leads.
    assert y[100] == pytest.approx(actuator[100] - 1.0)
    assert y[-1] == pytest.approx(actuator[-1] + 1.0)


def test_angle_dependent_velocity_scales_by_direction():
    effect = AngleDependentVelocity(0.25, 0.0)
    model = JointModel('j', LinearMap(10.0), 0.0, effects=(effect,))
    up = simulate(model, np.full(3, 1.0), 0.01, 0.0)
    down = simulate(model, np.full(3, -1.0), 0.01, 0.0)
    assert (up[1] - up[0]) / 0.01 == pytest.approx(10.0 * 1.25)     # cos(0) = 1
    assert (down[1] - down[0]) / 0.01 == pytest.approx(-10.0 * 0.75)
    at_90 = simulate(model, np.full(3, 1.0), 0.01, 90.0)
    assert (at_90[1] - at_90[0]) / 0.01 == pytest.approx(10.0, abs=1e-9)


def test_direction_dependent_delay(j2):
    model = j2.with_effect(DirectionDependentDelay(positive=0.1, negative=0.3))
    up = simulate(model, np.full(50, 3.0), 0.01, 20.0)
    down = simulate(model, np.full(50, -3.0), 0.01, 20.0)
    assert up[9] == 20.0 and up[10] > 20.0
    assert down[29] == 20.0 and down[30] < 20.0


def test_bad_commands_are_refused(j2):
    with pytest.raises(DataError, match='not finite'):
        simulate(j2, np.array([0.0, np.nan]), 0.01, 0.0)
    with pytest.raises(DataError, match='1-D'):
        simulate(j2, np.zeros((2, 2)), 0.01, 0.0)
    with pytest.raises(DataError, match='finite'):
        JointSimulator(j2, 0.01, 0.0).step(math.inf)
    assert simulate(j2, np.empty(0), 0.01, 0.0).size == 0


@pytest.mark.parametrize('held', [1, 3, 40], ids=['every-sample', 'short-runs', 'held-levels'])
def test_bounded_cumsum_matches_the_recursion(rng, held):
    increments = np.repeat(rng.normal(0.0, 1.0, 50_000 // held), held)
    x, expected = 5.0, [4.0]
    for d in increments:
        x = min(max(x + d, -3.0), 4.0)
        expected.append(x)
    result = bounded_cumsum(5.0, increments, -3.0, 4.0)
    np.testing.assert_allclose(result, expected, atol=1e-9)
    assert np.sum(result == 4.0) > 100 and np.sum(result == -3.0) > 100


@settings(max_examples=200, deadline=None)
@given(st.lists(st.floats(-10.0, 10.0), min_size=1, max_size=400),
       st.floats(-50.0, 100.0), st.sampled_from([0.01, 0.02, 0.05, 0.1]),
       st.sampled_from(range(len(EFFECT_SETS))))
def test_angle_never_leaves_the_end_stops(j2, commands, y0, dt, which):
    model = JointModel('j2', j2.static_map, j2.delay, j2.angle_limits,
                       effects=EFFECT_SETS[which])
    y = simulate(model, np.array(commands), dt, y0)
    assert np.all(y >= -13.8) and np.all(y <= 63.6)


STROKE = StrokeGeometry(knots=(-10.0, 10.0, 40.0, 60.0), factors=(0.6, 1.4, 1.1, 0.7),
                        asymmetry=(0.1, 0.0, -0.2, 0.05), cushion=4.0, cushion_factor=0.3)


def test_stroke_geometry_scales_the_speed_by_the_angle_the_same_way_both_ways():
    assert STROKE.factor_at(10.0, 1.0) == pytest.approx(1.4)
    assert STROKE.factor_at(25.0, 1.0) == pytest.approx(1.25 * (1.0 - 0.1))
    assert STROKE.factor_at(25.0, -1.0) == pytest.approx(1.25 * (1.0 + 0.1))
    # At 58 deg, 9/10 of the way from the 40 to the 60 deg knot: factor 1.1 - 0.9 * 0.4 =
    # 0.74, asymmetry -0.2 + 0.9 * 0.25 = 0.025. Cushion: heading for the upper end, 2 deg
    # before it, half way from 1 to 0.3.
    assert STROKE.factor_at(58.0, 1.0) == pytest.approx(0.74 * (1.0 + 0.025) * 0.65)
    # Leaving the upper end is not cushioned; flat beyond the end knots.
    assert STROKE.factor_at(58.0, -1.0) == pytest.approx(0.74 * (1.0 - 0.025))
    assert STROKE.factor_at(-30.0, 1.0) == pytest.approx(0.6 * 1.1)
    assert STROKE.factor_at(-30.0, -1.0) == pytest.approx(0.6 * 0.9 * 0.3)


def test_stroke_geometry_simulates_alike_vectorised_and_step_by_step(j2):
    model = replace(j2, angle_limits=(-10.0, 60.0), effects=(STROKE, ValveLag(0.05)))
    rng = np.random.default_rng(2)
    v = np.repeat(rng.uniform(-9.0, 9.0, 40), 60)
    y = simulate(model, v, 0.01, 20.0, v_before=v[0])
    sim = JointSimulator(model, 0.01, 20.0, v_before=v[0])
    stepped = np.r_[20.0, [sim.step(float(command)) for command in v[1:]]]
    np.testing.assert_allclose(stepped, y, rtol=0, atol=1e-9)
    # The factor matters: without it the path differs by degrees.
    plain = simulate(replace(model, effects=(ValveLag(0.05),)), v, 0.01, 20.0, v_before=v[0])
    assert np.max(np.abs(plain - y)) > 1.0

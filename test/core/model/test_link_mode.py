"""The link's mode on the oil column (effect ``oscillation``) against independent solutions."""

import math

from hydro_sdp.core.errors import DataError, ModelFileError
from hydro_sdp.core.model.effects import Backlash, Oscillation
from hydro_sdp.core.model.joint_model import JointModel
from hydro_sdp.core.model.link_mode import LinkMode, LinkState
from hydro_sdp.core.model.simulation import _ringing_increments, one_step_increments, simulate
from hydro_sdp.core.model.static_maps import SdpMap
import numpy as np
import pytest
from scipy.linalg import expm
from support.joint_generator import Joint, Machine, SpeedMap
from support.joint_generator import simulate as generate
from support.stepped_ringing import stepped_ringing_increments, strokes_into_stops

MAP = SdpMap(dead_zone=(-1.0, 1.2), saturation_velocity=(-30.0, 35.0), curvature=(0.8, 0.9))


@pytest.mark.parametrize('frequency, damping, dt', [(2.0, 0.1, 0.01), (3.5, 0.3, 0.05),
                                                    (0.5, 0.02, 0.001)])
def test_the_mode_is_the_exact_zero_order_hold_of_its_equation(frequency, damping, dt):
    # s = [y - x, y'], s' = A s + [-1, 0]' w with the actuator's speed w held over a sample:
    # the augmented exponential [[A, b], [0, 0]] dt gives P and G exactly.
    w = 2.0 * math.pi * frequency
    augmented = np.zeros((3, 3))
    augmented[:2, :2] = [[0.0, 1.0], [-w * w, -2.0 * damping * w]]
    augmented[0, 2] = -1.0
    exact = expm(augmented * dt)
    mode = LinkMode.of(Oscillation(frequency, damping), dt)
    np.testing.assert_allclose(np.reshape(mode.transition, (2, 2)), exact[:2, :2], atol=1e-13)
    np.testing.assert_allclose(mode.input_gain, exact[:2, 2], atol=1e-13)
    assert mode.lead == pytest.approx(2.0 * damping / w)


@pytest.mark.parametrize('mode', [(2.0, 0.1), (3.0, 0.05)])
def test_simulate_follows_the_independent_generators_mass_on_a_spring(mode):
    # The generator integrates y'' = w^2 (x - y) - 2 d w y' by Runge-Kutta within its own
    # sub-steps, from the physics; no stops here, random levels through the dead-zone.
    rng = np.random.default_rng(2)
    v = np.repeat(rng.uniform(-6.0, 6.0, 30), 100)
    truth = Joint(SpeedMap('exp', (-1.0, 1.2), (30.0, 35.0), (0.8, 0.9)), delay=0.1,
                  mode=mode, noise=0.0)
    expected = generate(Machine((truth,)), v[:, None], angles0=[0.0])[:, 0]
    model = JointModel('joint', MAP, 0.1, effects=(Oscillation(*mode),))
    y = simulate(model, v, 0.01, 0.0, v_before=v[0])
    plain = simulate(model.without_effect('oscillation'), v, 0.01, 0.0, v_before=v[0])
    assert np.max(np.abs(y - expected)) < 1e-5
    # The ringing is no small correction: the link swings a degree and more about the actuator.
    assert np.max(np.abs(y - plain)) > 1.0


def test_a_link_moving_steadily_trails_the_actuator_without_ringing():
    # Settled at a speed w the link lags the actuator by 2 d w / w_n and rings not at all.
    model = JointModel('joint', MAP, 0.1, effects=(Oscillation(2.0, 0.1),))
    v = np.full(300, 5.0)
    y = simulate(model, v, 0.01, 10.0, v_before=5.0)
    speed = float(model.rate(5.0))
    np.testing.assert_allclose(np.diff(y), 0.01 * speed, rtol=1e-9)
    plain = simulate(model.without_effect('oscillation'), v, 0.01, 10.0, v_before=5.0)
    lead = 2.0 * 0.1 * speed / (2.0 * math.pi * 2.0)
    np.testing.assert_allclose(plain + lead - y, lead, atol=1e-9)


def test_the_one_step_prediction_of_the_models_own_angles_is_exact():
    model = JointModel('joint', MAP, 0.15, effects=(Oscillation(2.5, 0.08),))
    rng = np.random.default_rng(4)
    v = np.repeat(rng.uniform(-5.0, 5.0, 20), 80)
    y = simulate(model, v, 0.01, 0.0, v_before=v[0])
    predicted = one_step_increments(model, v, y, 0.01, start=50, v_before=v[0])
    np.testing.assert_allclose(predicted, np.diff(y[50:]), atol=1e-9)


def test_at_the_stops_the_prediction_follows_the_generators_rebound():
    # Full strokes into both stops: the actuator stops dead, the link swings on and the
    # sensor reads the stop while the link is beyond it. The model's one-step prediction
    # from the generator's noise-free angles leaves a residual far below the ringing's.
    limits = (-2.0, 70.0)
    v = np.r_[np.full(120, 0.0), np.full(500, 5.0), np.full(150, 0.0), np.full(500, -5.0)]
    truth = Joint(SpeedMap('exp', (-1.0, 1.2), (30.0, 35.0), (0.8, 0.9)), delay=0.1,
                  stops=limits, mode=(3.0, 0.07), noise=0.0)
    y = generate(Machine((truth,)), v[:, None], angles0=[0.0])[:, 0]
    model = JointModel('joint', MAP, 0.1, angle_limits=limits,
                       effects=(Oscillation(3.0, 0.07),))
    predicted = one_step_increments(model, v, y, 0.01, start=100, v_before=v[0])
    residual = np.diff(y[100:]) - predicted
    plain = one_step_increments(model.without_effect('oscillation'), v, y, 0.01, start=100,
                                v_before=v[0])
    ringing = np.diff(y[100:]) - plain
    assert np.sum(residual ** 2) < 0.02 * np.sum(ringing ** 2)
    assert y.max() == limits[1] and y.min() == limits[0]


def test_the_model_file_reads_and_writes_the_mode(j2):
    model = j2.with_effect(Oscillation(2.2, 0.12)).with_effect(Backlash(0.5))
    data = model.to_mapping()
    assert data['effects']['oscillation'] == {'frequency': 2.2, 'damping': 0.12}
    # Effects are kept in the order the simulation applies them: the mode before the play.
    assert list(data['effects']) == ['oscillation', 'backlash']
    assert JointModel.from_mapping(data) == model


@pytest.mark.parametrize('params, message', [
    ({'frequency': 0.0, 'damping': 0.1}, 'frequency.*> 0 Hz'),
    ({'frequency': 2.0, 'damping': 1.0}, 'damping.*inside \\(0, 1\\)'),
    ({'frequency': 2.0, 'damping': 0.0}, 'damping.*inside \\(0, 1\\)'),
    ({'frequency': 2.0}, "missing parameter 'damping'"),
])
def test_a_bad_mode_is_refused_naming_its_key(j2, params, message):
    data = j2.to_mapping()
    data['effects'] = {'oscillation': params}
    with pytest.raises(ModelFileError, match=message):
        JointModel.from_mapping(data)


def test_a_mode_above_the_nyquist_frequency_is_refused(j2):
    model = j2.with_effect(Oscillation(12.0, 0.1))
    with pytest.raises(DataError, match='12 Hz is not below the Nyquist frequency of .* 0.05 s'):
        simulate(model, np.zeros(10), 0.05, 0.0)


@pytest.mark.parametrize('frequency, damping, dt', [
    (0.5, 0.02, 0.01), (2.0, 0.1, 0.01), (4.5, 0.6, 0.005), (20.0, 0.95, 0.01)])
def test_the_closed_form_modes_match_stepping_the_state_and_numpys_eigenvectors(
        frequency, damping, dt):
    # states() filters the actuator's speeds in the modal coordinates it forms in closed
    # form; stepped one sample at a time (LinkState) and through numpy's eig and inv
    # (the modal form it replaced) the link goes the same way.
    mode = LinkMode.of(Oscillation(frequency, damping), dt)
    speeds = np.random.default_rng(3).normal(0.0, 20.0, 400).cumsum() * 0.05
    e, u = mode.states(speeds, 7.0)
    state = LinkState(mode, 7.0)
    stepped = np.array([state.step(w) for w in speeds])
    np.testing.assert_allclose(e, stepped, rtol=1e-9, atol=1e-9 * np.max(np.abs(stepped)))
    poles, vectors = np.linalg.eig(np.array(mode.transition).reshape(2, 2))
    inverse = np.linalg.inv(vectors)
    pole, column, row = mode.modal
    k = int(np.argmin(np.abs(poles - pole)))
    assert poles[k] == pytest.approx(pole, rel=1e-12)
    # An eigenvector's scale is free; the projection column x row is not.
    np.testing.assert_allclose(np.outer(column, row), np.outer(vectors[:, k], inverse[k]),
                               rtol=1e-9, atol=1e-12)


@pytest.mark.parametrize('frequency, damping', [(0.6, 0.03), (2.0, 0.1), (4.0, 0.5)])
def test_the_stretches_at_the_stops_follow_the_recursion_stepped_sample_by_sample(
        frequency, damping):
    # Records that press and leave their stops many times, each stretch longer or shorter
    # than the chunks the fast form follows at once.
    mode = LinkMode.of(Oscillation(frequency, damping), 0.01)
    pressed = 0
    for seed in range(40):
        increment, angles, before, (low, high) = strokes_into_stops(seed)
        stepped = stepped_ringing_increments(mode, increment, angles, 0.01, before, low, high)
        fast = _ringing_increments(mode, increment, angles, 0.01, before, low, high)
        np.testing.assert_allclose(fast, stepped, rtol=0.0, atol=1e-9)
        pressed += int(np.sum(angles == high) + np.sum(angles == low))
    assert pressed > 1000

"""The design plant with the model's delay and valve lag, checked against python-control."""

from hydro_sdp.core.control.controller_spec import ControllerSpec, design_from_model
from hydro_sdp.core.control.design_plant import (
    completed_poles, lagged_integrator, plant_for_model)
from hydro_sdp.core.control.loop_noise import noise_gain
from hydro_sdp.core.control.pip_design import (
    closed_loop_poles, DiscretePlant, lq_design, LqWeights, nmss, pole_assignment)
from hydro_sdp.core.errors import ConfigurationError, ModelFileError
from hydro_sdp.core.model.effects import Oscillation, ValveLag
from hydro_sdp.core.model.joint_model import JointModel
from hydro_sdp.core.model.simulation import JointSimulator
from hydro_sdp.core.model.static_maps import LinearMap
import numpy as np
import pytest


@pytest.fixture(scope='module')
def control():
    """Return python-control, imported by the worker that runs this module only (2 s)."""
    return pytest.importorskip('control')


@pytest.mark.parametrize('time_constant, period', [(0.12, 0.05), (0.3, 0.05), (0.05, 0.1),
                                                   (0.02, 0.05)])
def test_the_lagged_integrator_is_python_controls_zero_order_hold(
        control, time_constant, period):
    # u in degrees per control sample asks for u / T deg/s through the lag 1 / (T_v s + 1).
    continuous = control.tf([1.0 / period], [time_constant, 1.0, 0.0])
    discrete = control.c2d(continuous, period, method='zoh')
    num, den = (np.ravel(x) for x in control.tfdata(discrete))
    num, den = num / den[0], den / den[0]
    plant = lagged_integrator(1, time_constant, period)
    # A(z^-1) = 1 + a1 z^-1 + a2 z^-2 is z^2 + a1 z + a2; B(z^-1) = b1 z^-1 + b2 z^-2 is b1 z + b2.
    np.testing.assert_allclose(den, np.r_[1.0, plant.a], rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(num[-2:], plant.b, rtol=1e-9, atol=1e-12)
    # A delay shifts B only; the steady gain stays one degree per degree asked.
    delayed = lagged_integrator(4, time_constant, period)
    assert delayed.delay == 4 and delayed.b[3:] == plant.b and delayed.a == plant.a
    assert sum(delayed.b) / (1.0 - delayed.a[1]) == pytest.approx(1.0)   # B(1) / (1 - p)


def test_the_plant_matches_the_model_simulated_finely():
    # A linear map (1 deg/s per unit) with a lag: the model stepped at 1 ms with the command
    # held over 50 ms control periods, sampled at the control instants, is the design plant's
    # response with the delay one control sample shorter (the model counts its delay to the
    # first sample that shows motion, docs/methods.md section 3.4).
    period, lag, delay = 0.05, 0.12, 0.2
    model = JointModel('j', LinearMap(gain=1.0), delay=delay,
                       effects=(ValveLag(lag),))
    plant = plant_for_model(model, period)
    assert (plant.n, plant.delay) == (2, 4)
    rng = np.random.default_rng(3)
    u = rng.normal(0.0, 1.0, 60)
    fine = 0.001
    every = int(round(period / fine))
    sim = JointSimulator(model, fine, 0.0)
    y_model = [sim.angle]
    for value in u:
        for _ in range(every):
            sim.step(value / period)          # u deg per control sample at 1 deg/s per unit
        y_model.append(sim.angle)
    # The design plant driven by u one control sample late.
    late = np.r_[0.0, u[:-1]]
    a, b = np.r_[1.0, plant.a], np.r_[0.0, plant.b]
    y = np.zeros(u.size + 1)
    for k in range(1, u.size + 1):
        y[k] = sum(-a[i] * y[k - i] for i in range(1, a.size) if k - i >= 0) \
            + sum(b[j] * late[k - j] for j in range(1, b.size) if k - j >= 0)
    # What is left is the model's own 1 ms steps (0.3 % here).
    np.testing.assert_allclose(y, y_model, atol=0.01 * np.max(np.abs(y)))


@pytest.mark.parametrize('delay', [1, 3, 8])
def test_pole_assignment_on_the_lagged_plant_places_the_poles(control, delay):
    plant = lagged_integrator(delay, 0.15, 0.05)
    poles = completed_poles(plant, [0.93 + 0.04j, 0.93 - 0.04j])
    assert len(poles) == plant.n + plant.m and poles[2] == pytest.approx(np.exp(-0.05 / 0.15))
    gains = pole_assignment(plant, poles)
    model = nmss(plant)
    reference = np.asarray(control.acker(model.F, model.g.reshape(-1, 1), poles)).ravel()
    np.testing.assert_allclose(gains.vector, reference, rtol=1e-6, atol=1e-9)
    closed = control.ss(model.F - np.outer(model.g, gains.vector), model.d.reshape(-1, 1),
                        model.h.reshape(1, -1), 0.0, 0.05)
    np.testing.assert_allclose(np.poly(control.poles(closed)), np.real(np.poly(poles)),
                               atol=1e-8)


@pytest.mark.parametrize('delay, lag', [(3, 0.12), (8, 0.12), (9, 0.065), (2, 0.4)])
def test_lq_on_the_lagged_plant_is_python_controls_dlqr(control, delay, lag):
    plant = lagged_integrator(delay, lag, 0.05)
    weights = LqWeights()
    gains = lq_design(plant, weights)
    model = nmss(plant)
    n, m = plant.n, plant.m
    q = np.diag(np.r_[np.full(n, weights.w_y / n), np.full(m - 1, weights.w_u / m), weights.w_e])
    k, _, eigenvalues = control.dlqr(model.F, model.g.reshape(-1, 1), q,
                                     np.array([[weights.w_u / m]]))
    np.testing.assert_allclose(gains.vector, np.ravel(k), rtol=1e-6, atol=1e-10)
    # Repeated poles near 0 scatter as a root of the rounding: compare the polynomials.
    np.testing.assert_allclose(np.poly(closed_loop_poles(plant, gains)), np.poly(eigenvalues),
                               atol=1e-9)
    # The paper's weights keep dominant poles near 0.94 +- 0.05i with a lag too.
    dominant = closed_loop_poles(plant, gains)[0]
    assert abs(dominant.real - 0.94) < 0.01 and abs(abs(dominant.imag) - 0.05) < 0.01


def test_a_design_records_its_plant_and_the_file_checks_it(j2, tmp_path):
    lagged = j2.with_effect(ValveLag(0.12))
    spec = design_from_model(lagged)
    assert spec.valve_lag == 0.12 and spec.plant == lagged_integrator(3, 0.12, 0.05)
    data = spec.to_mapping()
    assert data['plant']['valve_lag'] == 0.12 and len(data['plant']['a']) == 2
    assert ControllerSpec.from_mapping(data) == spec
    with pytest.raises(ModelFileError, match='valve lag of 0.2 s'):
        ControllerSpec.from_mapping({**data, 'plant': {**data['plant'], 'valve_lag': 0.2}})
    with pytest.raises(ModelFileError, match="key 'plant'"):
        ControllerSpec.from_mapping({**data, 'plant': {**data['plant'], 'lag': 0.2}})
    # Without a lag the design is the paper's: the integrator, nothing recorded.
    plain = design_from_model(j2).to_mapping()
    assert plain['plant'] == {'a': [-1.0], 'b': [0.0, 0.0, 1.0]}


def test_refusals():
    with pytest.raises(ConfigurationError, match='time constant > 0'):
        lagged_integrator(3, 0.0, 0.05)
    with pytest.raises(ConfigurationError, match='at least one sample'):
        lagged_integrator(0, 0.1, 0.05)
    assert lagged_integrator(3, None, 0.05) == DiscretePlant.integrator(3)


def _noise_to_u(plant, gains, samples=3000):
    """Return u after a unit impulse on the measured angle, by the loop's own equations."""
    a, b = np.r_[1.0, plant.a], np.r_[0.0, plant.b]
    y, u = np.zeros(samples), np.zeros(samples)

    def measured(k):
        return 0.0 if k < 0 else y[k] + (1.0 if k == 0 else 0.0)
    for k in range(samples):
        y[k] = sum(-a[i] * y[k - i] for i in range(1, a.size) if k - i >= 0) \
            + sum(b[j] * u[k - j] for j in range(1, b.size) if k - j >= 0)
        past = [u[k - j] if k - j >= 0 else 0.0 for j in range(1, plant.m + 1)]
        u[k] = past[0] - gains.k_i * measured(k) \
            - sum(f * (measured(k - i) - measured(k - i - 1)) for i, f in enumerate(gains.f)) \
            - sum(g * (past[j] - past[j + 1]) for j, g in enumerate(gains.g))
    return u


@pytest.mark.parametrize('lag', [None, 0.12])
def test_the_noise_gain_is_the_loops_own(j2, lag):
    model = j2 if lag is None else j2.with_effect(ValveLag(lag))
    spec = design_from_model(model, poles=None)
    expected = float(np.sqrt(np.sum(_noise_to_u(spec.plant, spec.gains) ** 2)))
    assert noise_gain(spec.plant, spec.gains) == pytest.approx(expected, rel=1e-9)
    # The values docs/methods.md section 5.5 quotes: [W18]'s J2 design, and the lagged
    # design, which reacts more to the angle's changes.
    assert expected == pytest.approx(0.1355 if lag is None else 0.4870, abs=5e-4)


@pytest.mark.parametrize('lag, frequency, damping, period', [
    (None, 2.0, 0.1, 0.05), (0.12, 2.0, 0.1, 0.05), (0.05, 3.5, 0.3, 0.1),
    (0.2, 1.0, 0.05, 0.02)])
def test_the_plant_with_a_mode_is_python_controls_zero_order_hold(
        control, lag, frequency, damping, period):
    # u deg per control sample asks for u / T deg/s through the lag and the link's mode
    # w^2 / (s^2 + 2 d w s + w^2), then the integrator.
    w = 2.0 * np.pi * frequency
    den = np.polymul([1.0, 0.0], [1.0, 2.0 * damping * w, w * w])
    if lag is not None:
        den = np.polymul(den, [lag, 1.0])
    discrete = control.c2d(control.tf([w * w / period], den), period, method='zoh')
    num, den = (np.ravel(x) for x in control.tfdata(discrete))
    num, den = num / den[0], den / den[0]
    plant = lagged_integrator(2, lag, period, (frequency, damping))
    assert plant.n == (4 if lag else 3) and plant.delay == 2
    np.testing.assert_allclose(den, np.r_[1.0, plant.a], atol=1e-12)
    np.testing.assert_allclose(num[-plant.n:], plant.b[1:], atol=1e-12)
    # The steady gain stays one degree per degree asked: B(1) = A(1) / (1 - z^-1) at z = 1.
    own = np.polydiv(np.r_[1.0, plant.a], [1.0, -1.0])[0]
    assert sum(plant.b) == pytest.approx(float(np.sum(own)))
    # The design keeps the mode's (and the lag's) poles and makes the rest deadbeat.
    poles = completed_poles(plant, [0.94 + 0.05j, 0.94 - 0.05j])
    np.testing.assert_allclose(np.poly(poles[2:2 + plant.n - 1]), own, atol=1e-12)
    assert len(poles) == plant.n + plant.m and not any(poles[1 + plant.n:])


def test_a_design_records_the_mode_and_the_file_checks_it(j2):
    ringing = j2.with_effect(ValveLag(0.12)).with_effect(Oscillation(2.0, 0.1))
    spec = design_from_model(ringing)
    assert spec.oscillation == (2.0, 0.1) and spec.plant == lagged_integrator(
        3, 0.12, 0.05, (2.0, 0.1))
    data = spec.to_mapping()
    assert data['plant']['oscillation'] == {'frequency': 2.0, 'damping': 0.1}
    assert ControllerSpec.from_mapping(data) == spec
    with pytest.raises(ModelFileError, match='mode of 2.5 Hz'):
        ControllerSpec.from_mapping({**data, 'plant': {
            **data['plant'], 'oscillation': {'frequency': 2.5, 'damping': 0.1}}})
    with pytest.raises(ModelFileError, match='plant.oscillation'):
        ControllerSpec.from_mapping({**data, 'plant': {
            **data['plant'], 'oscillation': {'frequency': 2.5}}})
    with pytest.raises(ConfigurationError, match='Nyquist'):
        lagged_integrator(3, None, 0.05, (12.0, 0.1))


def test_the_design_on_the_mode_steps_a_ringing_joint_without_sustained_ringing(j2, tmp_path):
    # The true joint is the independent generator's: J2's map and delay, its link ringing at
    # 2 Hz with a damping ratio of 0.1; the controller file runs in the independent loop.
    from hydro_sdp.io.controller_files import save_controller
    from support.independent_loop import FileController, judge, run_loop
    from support.joint_generator import GeneratedPlant, Joint, SpeedMap

    j2_map = j2.static_map
    truth = Joint(SpeedMap('exp', j2_map.dead_zone, (-j2_map.saturation_velocity[0],
                                                     j2_map.saturation_velocity[1]),
                           j2_map.curvature), delay=j2.delay, stops=j2.angle_limits,
                  mode=(2.0, 0.1), noise=0.02)
    levels = (10.0, 30.0, 50.0, 30.0, 10.0, 35.0)
    path = save_controller(design_from_model(j2.with_effect(Oscillation(2.0, 0.1))),
                           tmp_path / 'ringing.yaml')
    run = run_loop(FileController.read(path), GeneratedPlant(truth, levels[0]), 0.01, levels,
                   8.0)
    steps = judge(run)
    assert all(s.settling < 4.0 and s.overshoot < 5.0 for s in steps), steps
    # No hold ends hunting, and none rings on: the last 2 s stay within half the band.
    assert all(s.reversals == 0 and s.wander < 0.25 for s in steps), steps


def test_on_a_slower_lighter_mode_only_the_design_on_it_keeps_the_loop(j2, tmp_path):
    # J2 ringing at 1.5 Hz, damping 0.05: the integrator's design drives the mode
    # unstable; the one on the mode settles every step (the valve still hunts a little).
    from hydro_sdp.io.controller_files import save_controller
    from support.independent_loop import FileController, judge, run_loop
    from support.joint_generator import GeneratedPlant, Joint, SpeedMap

    j2_map = j2.static_map
    truth = Joint(SpeedMap('exp', j2_map.dead_zone, (-j2_map.saturation_velocity[0],
                                                     j2_map.saturation_velocity[1]),
                           j2_map.curvature), delay=j2.delay, stops=j2.angle_limits,
                  mode=(1.5, 0.05), noise=0.02)
    levels = (10.0, 30.0, 50.0)
    judged = {}
    for name, model in (('mode', j2.with_effect(Oscillation(1.5, 0.05))), ('plain', j2)):
        path = save_controller(design_from_model(model), tmp_path / f'{name}.yaml')
        judged[name] = judge(run_loop(FileController.read(path),
                                      GeneratedPlant(truth, levels[0]), 0.01, levels, 8.0))
    assert all(s.settling < 4.0 and s.overshoot < 5.0 for s in judged['mode']), judged
    assert all(s.settling == np.inf and s.overshoot > 15.0 for s in judged['plain']), judged


def test_a_slower_redesign_keeps_the_modes_poles_and_slows_the_dominant_ones(j2):
    from hydro_sdp.core.calibration import _slower
    from hydro_sdp.core.control.design_plant import mode_poles

    spec = design_from_model(j2.with_effect(Oscillation(2.0, 0.1)))
    pair = mode_poles((2.0, 0.1), 0.05)
    poles = _slower(spec)
    for pole in pair:
        assert min(abs(p - pole) for p in poles) < 1e-9
    slower = design_from_model(j2.with_effect(Oscillation(2.0, 0.1)), poles=poles)
    # The slow poles are placed (the repeated deadbeat ones computed only to 1e-4).
    np.testing.assert_allclose(sorted(abs(p) for p in slower.poles if abs(p) > 0.01),
                               sorted(abs(p) for p in poles if abs(p) > 0.01), atol=1e-6)
    dominant = max((p for p in spec.poles if min(abs(p - m) for m in pair) > 0.05), key=abs)
    assert max(abs(p) for p in poles if min(abs(p - m) for m in pair) > 1e-6) > abs(dominant)

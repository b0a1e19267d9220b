"""The runtime PIP-IDZ controller: the incremental law, IDZ, limits, anti-windup, safety."""

from dataclasses import replace
import math

from hydro_sdp.core.control.idz import InverseDeadZone
from hydro_sdp.core.control.pip_controller import ControllerSettings, PipIdzController
from hydro_sdp.core.control.pip_design import PipGains
from hydro_sdp.core.errors import ConfigurationError, DataError
from hypothesis import given, settings, strategies as st
import numpy as np
import pytest

PAPER = PipGains((0.1261,), (0.12, 0.1261), 0.0061)
J2_IDZ = InverseDeadZone((-1.3298, 1.3124), (1.1746, 2.3951), beta=0.05)


def test_incremental_law_is_eq_8(rng):
    controller = PipIdzController(ControllerSettings(PAPER))
    f0, (g1, g2), k_i = PAPER.f[0], PAPER.g, PAPER.k_i
    u = [0.0, 0.0, 0.0]           # u_{k-1}, u_{k-2}, u_{k-3}
    y_previous = None
    for _ in range(50):
        d, y = rng.uniform(-20, 20), rng.uniform(-20, 20)
        y_previous = y if y_previous is None else y_previous
        expected = (u[0] - g1 * (u[0] - u[1]) - g2 * (u[1] - u[2]) - f0 * (y - y_previous)
                    + k_i * (d - y))
        got, v = controller.step(d, y)
        assert got == pytest.approx(expected, abs=1e-12)
        assert v == got            # no IDZ: the valve gets u
        u = [got] + u[:2]
        y_previous = y


def test_clamped_u_is_stored_back():
    controller = PipIdzController(ControllerSettings(PAPER, u_limits=(-2.5, 2.5)))
    for _ in range(200):
        u, _ = controller.step(60.0, 0.0)
    assert u == 2.5
    # With a free integrator the demand would be far above the limit; here one
    # step of error reversal already moves u off the limit.
    u, _ = controller.step(-60.0, 0.0)
    assert u < 2.5


def test_valve_limit_is_back_calculated_through_the_idz():
    settings = ControllerSettings(PAPER, J2_IDZ, u_limits=(-10.0, 10.0), v_limits=(-2.0, 2.0))
    controller = PipIdzController(settings)
    for _ in range(100):
        u, v = controller.step(60.0, 0.0)
    assert v == 2.0
    # The stored u is what a 2 V command gives, not what was asked for.
    assert u == pytest.approx(J2_IDZ.increment(2.0))
    assert controller.last_u == pytest.approx(2.3951 * (2.0 - 1.3124))


def test_zero_band_idz_is_eq_7():
    for u in np.linspace(-3, 3, 121):
        v, _ = J2_IDZ.command(u)
        if abs(u) <= 0.05:
            assert v == 0.0
        else:
            assert J2_IDZ.increment(v) == pytest.approx(u, abs=1e-12)
            expected = u / 1.1746 - 1.3298 if u < 0 else u / 2.3951 + 1.3124
            assert v == pytest.approx(expected)


def test_smooth_idz_is_continuous_and_inverts_outside_the_band():
    smooth = replace(J2_IDZ, mode='smooth')
    u = np.linspace(-1.0, 1.0, 2001)
    v = np.array([smooth.command(x)[0] for x in u])
    assert np.max(np.abs(np.diff(v))) < 0.05          # no jump between the edges
    far = np.abs(u) > 0.5
    np.testing.assert_allclose([smooth.increment(x) for x in v[far]], u[far], atol=1e-3)


def test_hysteresis_idz_switches_only_outside_the_band():
    hysteresis = replace(J2_IDZ, mode='hysteresis')
    v, branch = hysteresis.command(0.0, 0)
    assert (v, branch) == (0.0, 0)
    v, branch = hysteresis.command(0.1, branch)
    assert branch == 1 and v > 1.3124
    v, branch = hysteresis.command(-0.04, branch)     # inside the band: keeps its branch
    assert branch == 1 and -1.3298 <= v < 1.3124
    v, branch = hysteresis.command(-0.06, branch)
    assert branch == -1 and v < -1.3298


def test_bad_inputs_are_refused_and_leave_the_state_alone():
    controller = PipIdzController(ControllerSettings(PAPER, J2_IDZ, (-2.5, 2.5), (-10, 10)))
    controller.step(10.0, 0.0)
    before = (controller.last_u, controller.last_v, controller.steps)
    for setpoint, y in ((math.nan, 0.0), (10.0, math.inf), (10.0, math.nan)):
        with pytest.raises(DataError, match='must be finite'):
            controller.step(setpoint, y)
    assert (controller.last_u, controller.last_v, controller.steps) == before


def test_idz_change_does_not_jump_the_command():
    controller = PipIdzController(ControllerSettings(PAPER, J2_IDZ, (-2.5, 2.5), (-10, 10)))
    for k in range(40):
        u, v = controller.step(30.0, 0.1 * k)
    assert v > 1.3124
    wider = replace(J2_IDZ, dead_zone=(-1.6, 1.6), slopes=(1.3, 2.2))
    controller.update_idz(wider)
    assert wider.command(controller.last_u, 1)[0] == pytest.approx(v)
    u_next, v_next = controller.step(30.0, 4.0)
    assert abs(v_next - v) < 0.1


def test_settings_are_validated():
    with pytest.raises(ConfigurationError, match='u_limits'):
        ControllerSettings(PAPER, u_limits=(1.0, -1.0))
    with pytest.raises(ConfigurationError, match='rest command'):
        ControllerSettings(PAPER, replace(J2_IDZ, rest=0.5), v_limits=(1.0, 2.0))
    with pytest.raises(ConfigurationError, match='slopes'):
        InverseDeadZone((-1.0, 1.0), (0.0, 1.0))
    with pytest.raises(ConfigurationError, match='mode'):
        InverseDeadZone((-1.0, 1.0), (1.0, 1.0), mode='magic')
    with pytest.raises(ConfigurationError, match='keep 1 f and 2 g'):
        PipIdzController(ControllerSettings(PAPER)).update_gains(PipGains((0.1,), (), 0.01))


@settings(max_examples=300, deadline=None)
@given(st.lists(st.tuples(st.floats(-1e6, 1e6), st.floats(-1e6, 1e6)), min_size=1,
                max_size=60),
       st.sampled_from(['zero', 'smooth', 'hysteresis']), st.floats(0.0, 0.5))
def test_command_is_always_finite_and_inside_the_limits(inputs, mode, beta):
    idz = replace(J2_IDZ, mode=mode, beta=beta)
    controller = PipIdzController(ControllerSettings(PAPER, idz, (-2.5, 2.5), (-10.0, 10.0)))
    for setpoint, y in inputs:
        u, v = controller.step(setpoint, y)
        assert math.isfinite(u) and math.isfinite(v)
        assert -2.5 <= u <= 2.5
        assert -10.0 <= v <= 10.0


@settings(max_examples=300, deadline=None)
@given(st.floats(-50.0, 50.0), st.floats(0.0, 0.5))
def test_dead_zone_after_idz_returns_u_outside_the_band(u, beta):
    idz = replace(J2_IDZ, beta=beta)
    v, _ = idz.command(u)
    if abs(u) > beta:
        assert idz.increment(v) == pytest.approx(u, rel=1e-12, abs=1e-12)
    else:
        assert idz.increment(v) == 0.0

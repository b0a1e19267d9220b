"""Nonlinear PIP-IDZ closed loops on the J2 model and on two LUCIE-like joints."""

from dataclasses import replace

from hydro_sdp.core.control.controller_spec import ControllerSpec, design_from_model, format_pole
from hydro_sdp.core.control.idz_design import idz_for_model
from hydro_sdp.core.control.loop_simulation import (
    LoopJoint, run_closed_loop, step_metrics, step_setpoints, valve_reversals)
from hydro_sdp.core.errors import ConfigurationError, ModelFileError
from hydro_sdp.core.model.simulation import simulate
from hydro_sdp.io.controller_files import load_controller, save_controller
from hydro_sdp.io.documents import shipped_config
from hydro_sdp.io.model_files import load_model
import numpy as np
import pytest

PAPER_POLES = [0.94 + 0.05j, 0.94 - 0.05j, 0.0, 0.0]
PRINTED_POLES = [0.9 + 0.05j, 0.9 - 0.05j, 0.0, 0.0]


def paper_controller(j2, poles=PAPER_POLES, **kwargs):
    """Design the paper's J2 controller: chords to -2.2 and 1.75 V, u within +-2.5."""
    kwargs.setdefault('u_limits', (-2.5, 2.5))
    return design_from_model(j2, poles=poles, v_range=(-2.2, 1.75), **kwargs)


def run_step(j2, spec, target, seconds=20.0, controller=None, **kwargs):
    joint = LoopJoint(j2, controller or spec.controller(),
                      step_setpoints([target], seconds, 0.01), 0.0)
    return run_closed_loop([joint], dt=0.01, control_period=0.05, **kwargs)[0]


def test_design_from_the_j2_model_uses_the_papers_slopes(j2):
    spec = paper_controller(j2)
    assert spec.delay_samples == 3
    np.testing.assert_allclose(spec.idz.slopes, (1.1746, 2.3951), atol=1e-4)
    assert spec.idz.dead_zone == (-1.3298, 1.3124)
    default = idz_for_model(j2, 0.05)   # chords to two thirds of saturation
    speeds = j2.rate(np.array([-1.3298 - np.log(3) / 1.356, 1.3124 + np.log(3) / 1.771]))
    np.testing.assert_allclose(speeds, [-29.51 * 2 / 3, 38.87 * 2 / 3])
    assert default.slopes[0] == pytest.approx(speeds[0] * 0.05 / (-np.log(3) / 1.356))


@pytest.mark.parametrize(('target', 'overshoot', 'settling'), [
    # docs/methods.md 4.6 (printed gains): 0.85 % / 2.15 s, 2.87 % / 2.90 s, 9.0 % / 4.25 s.
    (20.0, 0.85, 2.15), (-10.0, 2.87, 2.90), (50.0, 9.0, 4.25)])
def test_j2_steps_settle_as_in_methods_4_6(j2, target, overshoot, settling):
    trace = run_step(j2, paper_controller(j2), target)
    metrics = step_metrics(trace, band=0.5, initial=0.0)[0]
    assert metrics.settling_time < 5.0
    assert metrics.overshoot < 10.0
    assert metrics.overshoot == pytest.approx(overshoot, abs=0.4)
    assert metrics.settling_time == pytest.approx(settling, abs=0.05)
    assert np.max(np.abs(trace.y[-1000:] - target)) < 0.35   # the chatter band's residue


class PositionalPip:
    """The same PIP law in positional form with a free integral state (it winds up)."""

    def __init__(self, spec):
        self.spec, self.u, self.z = spec, [0.0, 0.0], 0.0
        self.last_u, self.last_v = 0.0, 0.0

    def step(self, setpoint, y):
        gains, idz = self.spec.gains, self.spec.idz
        self.z += setpoint - y
        u = -gains.f[0] * y - gains.g[0] * self.u[0] - gains.g[1] * self.u[1] + gains.k_i * self.z
        u = min(max(u, self.spec.u_limits[0]), self.spec.u_limits[1])
        self.u = [u, self.u[0]]
        v, _ = idz.command(u)
        self.last_u, self.last_v = u, v
        return u, v


def test_incremental_form_does_not_wind_up_on_a_60_degree_step(j2):
    spec = paper_controller(j2, PRINTED_POLES)
    incremental = run_step(j2, spec, 60.0, 30.0)
    positional = run_step(j2, spec, 60.0, 30.0, controller=PositionalPip(spec))
    fast = step_metrics(incremental, initial=0.0)[0]
    slow = step_metrics(positional, initial=0.0)[0]
    assert np.max(incremental.u) == 2.5                      # u saturates
    # docs/methods.md section 6: 3.55 s (4.5 %) against 7.40 s (6.0 %) for the positional form.
    assert fast.settling_time == pytest.approx(3.55, abs=0.1)
    assert slow.settling_time > 1.8 * fast.settling_time
    assert slow.overshoot > fast.overshoot


def test_idz_edges_outside_the_true_ones_make_a_limit_cycle(j2):
    spec = paper_controller(j2)
    low, high = spec.idz.dead_zone
    runs = {}
    for label, edges in (('true', (low, high)), ('wide', (low - 0.1, high + 0.1)),
                         ('narrow', (low + 0.1, high - 0.1))):
        trace = run_step(j2, replace(spec, idz=replace(spec.idz, dead_zone=edges)), 20.0, 30.0)
        tail = trace.y[-1000:] - 20.0
        runs[label] = (np.ptp(tail), valve_reversals(trace.v[-1000:]),
                       step_metrics(trace, initial=0.0)[0])
    # Over-compensation hunts in a +-0.8 deg limit cycle (docs/methods.md section 4.6) ...
    assert runs['wide'][0] > 1.2 and runs['wide'][1] >= 10
    assert runs['wide'][2].settling_time > 20.0       # in and out of the band to the end
    # ... while the right edges, and edges a little inside the true ones, settle.
    for label in ('true', 'narrow'):
        assert runs[label][0] < 0.4 and runs[label][1] <= 2
        assert runs[label][2].settling_time < 3.0


def test_chatter_band_stops_valve_reversals(j2):
    reversals = {}
    for beta in (0.0, 0.05):
        spec = paper_controller(j2, beta=beta)
        trace = run_step(j2, spec, 20.0, 40.0, noise_std=0.01, seed=3)
        reversals[beta] = valve_reversals(trace.v[-2000:])   # the last 20 s
    assert reversals[0.0] > 100       # docs/methods.md section 5.2: about every sample
    assert reversals[0.05] <= 2


def test_trace_replays_through_the_open_loop_simulation(j2):
    trace = run_step(j2, paper_controller(j2), 30.0, 8.0, noise_std=0.02, seed=1)
    replay = simulate(j2, trace.v, 0.01, 0.0, v_before=trace.v[0])
    np.testing.assert_allclose(replay, trace.y, atol=1e-9)
    assert np.all(trace.u[1:6] == trace.u[1])     # u is held between control instants


def test_two_joints_track_simultaneous_ramps():
    boom = load_model(shipped_config('lucie_boom.yaml'))
    dipper = load_model(shipped_config('lucie_dipper.yaml'))
    dt, period = 0.02, 0.1
    t = np.arange(0.0, 40.0, dt)
    ramps = {'boom': np.interp(t, [0, 5, 25, 40], [0.0, 0.0, 30.0, 30.0]),
             'dipper': np.interp(t, [0, 5, 25, 40], [-100.0, -100.0, -60.0, -60.0])}
    joints = []
    for model in (boom, dipper):
        spec = design_from_model(model, control_period=period)
        assert spec.delay_samples == 1                     # unit delay at 0.1 s
        joints.append(LoopJoint(model, spec.controller(), ramps[model.joint],
                                ramps[model.joint][0]))
    traces = run_closed_loop(joints, dt=dt, control_period=period)
    for joint, trace in zip(joints, traces):
        error = trace.y - trace.setpoint
        # On a ramp of r deg per control sample the incremental law settles where
        # -f0 r + kI e = 0: PIP lags a ramp by e = f0 r / kI, then catches up.
        gains = joint.controller.settings.gains
        rate = np.ptp(ramps[trace.joint]) / 20.0 * period
        lag = gains.f[0] * rate / gains.k_i
        ramp = (trace.t > 15.0) & (trace.t < 25.0)
        np.testing.assert_allclose(-error[ramp], lag, rtol=0.1)
        assert np.max(np.abs(error[trace.t > 35.0])) < 0.5
    assert np.ptp(traces[0].v) > 50.0 and np.ptp(traces[1].v) > 50.0  # drive-demand units


def test_controller_file_round_trip_and_checks(j2, tmp_path):
    spec = paper_controller(j2)
    path = save_controller(spec, tmp_path / 'controller.yaml')
    loaded = load_controller(path)
    assert loaded == spec
    assert [format_pole(p) for p in loaded.poles] == ['0.94+0.05j', '0.94-0.05j', '0+0j',
                                                      '0+0j']
    data = spec.to_mapping()
    with pytest.raises(ModelFileError, match='unstable'):
        ControllerSpec.from_mapping({**data, 'kI': -0.5})
    with pytest.raises(ModelFileError, match="unknown key 'gain'"):
        ControllerSpec.from_mapping({**data, 'gain': 1.0})
    with pytest.raises(ModelFileError, match="key 'delay_samples'"):
        ControllerSpec.from_mapping({**data, 'delay_samples': 4})
    with pytest.raises(ModelFileError, match='do not fit'):
        ControllerSpec.from_mapping({**data, 'g': [0.1]})
    with pytest.raises(ModelFileError, match="key 'idz.mode'"):
        ControllerSpec.from_mapping({**data, 'idz': {**data['idz'], 'mode': 'fuzzy'}})
    with pytest.raises(ModelFileError, match="key 'design'"):
        ControllerSpec.from_mapping({**data, 'design': 'lq'})


def test_closed_loop_refuses_mismatched_periods(j2):
    spec = paper_controller(j2)
    joint = LoopJoint(j2, spec.controller(), np.zeros(10))
    with pytest.raises(ConfigurationError, match='whole multiple'):
        run_closed_loop([joint], dt=0.03, control_period=0.05)

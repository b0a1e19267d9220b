"""Simulations restarted from the measured angle: each window is the simulation from its start."""

from hydro_sdp.core.diagnosis.residuals import runs_of
from hydro_sdp.core.identification.evaluation import record_mae
from hydro_sdp.core.identification.held_out import WindowErrors
from hydro_sdp.core.model.effects import Backlash, StrokeGeometry, ValveLag
from hydro_sdp.core.model.records import Record
from hydro_sdp.core.model.simulation import simulate, speed_profile
from hydro_sdp.core.model.windows import simulate_windows
import numpy as np
import pytest

DT = 0.01


def commands(rng, n=1200):
    return np.repeat(rng.choice([-4.0, -2.5, 0.0, 2.5, 4.0], size=n // 100), 100)


def test_each_window_is_the_simulation_from_its_start(j2, rng):
    model = j2.with_effect(ValveLag(0.1)).with_effect(
        StrokeGeometry((-20.0, 20.0, 60.0), (0.8, 1.2, 0.9)))
    v = commands(rng)
    y = simulate(model, v, DT, 20.0, v_before=v[0]) + rng.normal(0.0, 0.05, v.size)
    starts = [20, 220, 420, 620]
    windows = simulate_windows(model, v, y, DT, starts, v_before=float(v[0]))
    assert np.all(np.isnan(windows[:20]))
    speed = speed_profile(model, v, DT, v_before=float(v[0]))
    for first, end in zip(starts, starts[1:] + [v.size]):
        # The lag's state runs on through the record; only the angle starts afresh.
        alone = simulate(model, v, DT, float(y[first]), v_before=float(v[0]), start=first)
        np.testing.assert_allclose(windows[first:end], alone[first:end], atol=1e-9)
        assert windows[first] == np.clip(y[first], *model.angle_limits)
    assert speed.size == windows.size


def test_the_play_starts_on_the_side_the_last_motion_took_it_up(j2):
    model = j2.with_effect(Backlash(2.0))
    v = np.r_[np.full(100, 3.0), np.full(100, 0.0), np.full(100, -3.0)]
    y = simulate(model, v, DT, 20.0, v_before=3.0)
    # Restarted at rest after moving up, the sensor is 1 deg behind the actuator: moving
    # down it stands still for 2 deg of travel, exactly as the whole simulation did.
    windows = simulate_windows(model, v, y, DT, [0, 150], v_before=3.0)
    np.testing.assert_allclose(windows[150:], y[150:], atol=1e-9)
    # Restarted with the play in the middle it would have moved 1 deg sooner.
    middle = simulate(model, v, DT, float(y[150]), v_before=3.0, start=150)
    assert np.max(np.abs(middle[150:] - y[150:])) > 0.5


def test_models_are_compared_over_the_same_samples(j2, rng):
    v = commands(rng, 3000)
    lagged = j2.with_effect(ValveLag(0.2))
    y = simulate(lagged, v, DT, 20.0, v_before=v[0]) + rng.normal(0.0, 0.02, v.size)
    record = Record(DT * np.arange(1, v.size + 1), v, y, joint=j2.joint)
    errors = WindowErrors(runs_of([record], 0.5))
    before, after = errors.compare([j2, lagged])
    # From the lag's later start (15 + 100 samples) for both; the true model is left with
    # the noise only.
    assert after < 0.05 < before
    whole = errors.compare([j2], None)[0]
    assert whole == pytest.approx(record_mae(j2, record), rel=1e-12)
    assert errors.compare([j2, lagged]) == [before, after]

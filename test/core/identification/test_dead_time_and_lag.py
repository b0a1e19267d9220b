"""Dead time and valve lag identified together: simulated J2 steps and the physics plant."""

from dataclasses import replace
import math

from hydro_sdp.core.identification.change_windows import (
    ChangeWindows, fit_delay_lag_and_pure, lag_pole)
from hydro_sdp.core.identification.delay import estimate_delay
from hydro_sdp.core.identification.experiment import Experiment, split_long
from hydro_sdp.core.identification.identify import identify
from hydro_sdp.core.identification.segmentation import segment_records, Segmentation
from hydro_sdp.core.model.effects import ValveLag
from hydro_sdp.core.model.joint_model import JointModel
from hydro_sdp.core.model.records import Record
from hydro_sdp.core.synthetic.joint_experiments import experiment_record
from hydro_sdp.core.synthetic.physics.parameters import Valve
from hydro_sdp.core.synthetic.physics.plant import with_payload
from hydro_sdp.core.synthetic.physics.runs import full_stroke_runs
from hydro_sdp.io.documents import shipped_config
from hydro_sdp.io.plant_files import load_machine
import numpy as np
import pytest

DT = 0.01
#: Duties of the physics runs, percent; 40 % barely moves either joint (1 deg/s).
DUTIES = (40, 50, 60, 70, 80, 90, 100)
PAYLOADS = {'arm': 250.0, 'boom': 600.0}
#: A preset's name, its valve and its full-stroke runs at high load.
Plant = tuple[str, Valve, list[Record]]


def j2_steps(j2: JointModel, delay: float, lag: float | None, noise: float,
             seed: int = 1) -> tuple[Segmentation, list[Experiment]]:
    """Return the step experiments of J2 with another delay and a valve lag (None: none)."""
    truth = replace(j2, delay=delay)
    truth = truth if lag is None else truth.with_effect(ValveLag(lag))
    record = experiment_record(truth, 'steps', seed=seed, noise=noise)
    segmentation = segment_records([record], max_delay=50)
    return segmentation, split_long(segmentation.experiments, 3000, 50)


@pytest.mark.parametrize('noise', [0.01, 0.03])
@pytest.mark.parametrize('lag', [0.05, 0.12, 0.25])
def test_dead_time_and_lag_of_j2_steps(j2: JointModel, lag: float, noise: float) -> None:
    for delay in (0.05, 0.15, 0.25):
        segmentation, pieces = j2_steps(j2, delay, lag, noise)
        found = estimate_delay(pieces, DT, max_delay=50, noise=segmentation.noise_std)
        assert abs(found.samples - round(delay / DT)) <= 1, (delay, found.samples, found.lag)
        assert found.lag == pytest.approx(lag, rel=0.05), (delay, found.samples, found.lag)
        # Cross-correlation with the lag's response to a change agrees.
        assert found.xcorr is not None and abs(found.xcorr - round(delay / DT)) <= 1


def test_identify_puts_the_lag_into_the_model(j2: JointModel) -> None:
    truth = j2.with_effect(ValveLag(0.12))
    result = identify([experiment_record(truth, 'steps', seed=2, noise=0.03)])
    assert result.delay.samples == 15
    lag = result.model.effect('valve_lag')
    assert isinstance(lag, ValveLag) and lag.time_constant == pytest.approx(0.12, rel=0.1)
    assert result.model.delay == pytest.approx(0.15)


def test_no_lag_is_found_where_there_is_none(j2: JointModel) -> None:
    segmentation, pieces = j2_steps(j2, 0.15, None, 0.03)
    delay, lag, explained, _ = fit_delay_lag_and_pure(pieces, DT, 50)
    assert (delay, lag) == (15, 0.0)
    assert int(np.argmax(explained)) + 1 == 15


def test_the_true_pair_leaves_only_the_noise(j2: JointModel) -> None:
    # Every window holds the samples where its change can show for any dead time up to
    # the largest, and no other change: all pairs are scored on the same samples, the
    # true one leaves the noise of the differenced angle (variance 2 noise^2) and its
    # neighbours (one sample, 0.02 s, or a short lag traded for a long delay) far more.
    noise = 1e-4
    _, pieces = j2_steps(j2, 0.15, 0.12, noise)
    windows = ChangeWindows(pieces, 50)
    truth = windows.residual(15, lag_pole(0.12, DT))
    assert truth <= 2.0 * noise ** 2 * windows.length.sum()
    for delay, lag in ((16, 0.12), (14, 0.12), (15, 0.10), (15, 0.14), (15, 0.0), (22, 0.04)):
        assert windows.residual(delay, lag_pole(lag, DT)) > 100.0 * truth, (delay, lag)


def plant_rise(record: Record, fraction: float) -> float:
    """Time from the command step to the first sample at ``fraction`` of the speed after it, s."""
    k0 = int(np.flatnonzero(record.v != record.v[0])[0])
    increments = np.diff(record.y[k0 - 1:])
    speed = np.convolve(increments, np.ones(3) / 3.0, mode='same')
    final = float(np.median(speed[80:130]))
    return float(np.flatnonzero(np.sign(final) * speed >= fraction * abs(final))[0]) * DT


def model_rise(delay: int, lag: float, fraction: float) -> float:
    """Return the same for a dead time (samples) and a first-order lag (s)."""
    p = lag_pole(lag, DT)
    rise = math.ceil(math.log(1.0 - fraction) / math.log(p)) - 1 if p > 0.0 else 0
    return (delay + rise) * DT


@pytest.fixture(scope='module', params=['arm', 'boom'])
def plant(request: pytest.FixtureRequest) -> Plant:
    machine = load_machine(shipped_config(f'physics_{request.param}.yaml'))
    heavy = with_payload(machine, PAYLOADS[request.param])
    return request.param, machine.joints[0].valve, full_stroke_runs(heavy, DT, DUTIES, seed=11)


def test_dead_time_and_lag_match_the_plants_step_responses(plant: Plant) -> None:
    name, valve, runs = plant
    segmentation = segment_records(runs, max_delay=50)
    found = estimate_delay(split_long(segmentation.experiments, 3000, 50), DT, max_delay=50,
                           noise=segmentation.noise_std)
    moving = [r for r in runs if abs(float(r.source.split()[-2])) >= 50.0]
    onsets = np.array([plant_rise(r, 0.1) for r in moving])
    rises = np.array([plant_rise(r, 0.632) for r in moving])
    # The plant has no single dead time: flow starts only once the spool (dead time,
    # then its lag) has crossed the overlap, later for smaller duties, and then rises
    # convexly with the opening. Each duty's onset lies within one spool time
    # constant after that opening time.
    travel = np.array([abs(float(r.source.split()[-2])) / 100.0 for r in moving])
    opening = valve.dead_time + valve.time_constant * np.log(travel / (travel - valve.overlap))
    assert np.all(onsets >= opening - DT)
    assert np.all(onsets <= opening + valve.time_constant)
    # One dead time and one lag after the map can only fall within that spread: the
    # identified onset (10 %) and 63 % rise time lie within those of the duties that
    # move the joint, to a sample.
    onset = model_rise(found.samples, found.lag, 0.1)
    rise = model_rise(found.samples, found.lag, 0.632)
    assert onsets.min() - DT <= onset <= onsets.max() + DT, (onset, onsets)
    assert rises.min() - DT <= rise <= rises.max() + DT, (rise, rises)
    # And nearer the plant's typical 63 % rise than the spool's own dead time plus lag.
    typical = float(np.median(rises))
    assert abs(rise - typical) < abs(valve.dead_time + valve.time_constant - typical)


def test_a_command_that_never_changes_gives_no_delay():
    # Every (delay, lag) pair would explain a record without a change: refused instead.
    from hydro_sdp.core.errors import DataError
    flat = Experiment(np.full(400, 2.0), np.linspace(0.0, 10.0, 400), 30, 'run', 2.0, 0.0)
    with pytest.raises(DataError, match='never changes'):
        fit_delay_lag_and_pure([flat], 0.01, 20)

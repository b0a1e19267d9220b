"""The diagnosis names flow sharing and load dependence on the physics plant."""

from dataclasses import replace
from pathlib import Path
from typing import Sequence

from hydro_sdp.core.diagnosis import diagnose, Diagnosis, runs_of
from hydro_sdp.core.diagnosis.context import Context
from hydro_sdp.core.diagnosis.detectors import detector
from hydro_sdp.core.identification.identify import identify
from hydro_sdp.core.model.effects import FlowSharing, LoadDependence
from hydro_sdp.core.model.exogenous_signals import Exogenous, exogenous_factor
from hydro_sdp.core.model.joint_model import JointModel
from hydro_sdp.core.model.records import Record
from hydro_sdp.core.synthetic.physics.hydraulics import Actuator
from hydro_sdp.core.synthetic.physics.plant import Machine, with_payload
from hydro_sdp.core.synthetic.physics.runs import full_stroke_runs
from hydro_sdp.io.documents import shipped_config
from hydro_sdp.io.plant_files import load_machine
from hydro_sdp.report.diagnosis import write_report
import numpy as np
import pytest
from support.diagnosis_grid import hide
from support.joint_generator import record
from support.plant_levels import plant_levels

pytestmark = [pytest.mark.slow, pytest.mark.usefixtures('figures_not_drawn')]

DT = 0.01
DUTIES = (55, 75, 100)
#: The model identified, the records with the boom still and moving, and the diagnosis.
Sharing = tuple[JointModel, list[Record], list[Record], Diagnosis]
#: The arm, the model identified without payload, and the runs without and with 1200 kg.
Payloads = tuple[Machine, JointModel, list[Record], list[Record]]


def levels(machine: Machine, duration: float, moving: Sequence[int], seed: int) -> Record:
    """
    Random duties held 0.5-3 s on the joints in ``moving``, each turned back before its stops.

    Returns the first joint's record with the second joint's angle as ``others``.
    """
    c, a = plant_levels(machine, DT, duration, moving, seed)
    return Record(DT * np.arange(1, len(c) + 1), c[:, 0], a[:, 0], machine.names[0],
                  f'levels {seed}', others=a[:, 1:], other_joints=machine.names[1:])


@pytest.fixture(scope='module')
def excavator() -> Machine:
    """Put the arm and the boom of the presets on the arm's pump (32.4 l/min)."""
    arm = load_machine(shipped_config('physics_arm.yaml'))
    boom = load_machine(shipped_config('physics_boom.yaml'))
    return replace(arm, joints=(arm.joints[0], boom.joints[0]))


@pytest.fixture(scope='module')
def sharing(excavator: Machine) -> Sharing:
    """Identify the arm with the boom still; diagnose it on runs with both moving."""
    alone = [levels(excavator, 40.0, [0], seed) for seed in (1, 2, 3)]
    plain = [Record(r.t, r.v, r.y, r.joint, r.source) for r in alone]
    model = identify(plain, kind='sdp').model
    both = [levels(excavator, 40.0, [0, 1], seed) for seed in (4, 5, 6)]
    # No validation given: the third recording is held out to judge on.
    return model, alone, both, diagnose(both, model, max_iterations=1)


def test_flow_sharing_is_named_first_and_the_gap_shrinks(
        sharing: Sharing, tmp_path: Path) -> None:
    model, _, both, result = sharing
    assert result.validation.startswith('held out: 1 of 3')
    written = [str(path) for path in write_report(tmp_path, result)]
    assert str(tmp_path / 'signature.png') in written
    assert str(tmp_path / 'record_scales.png') not in written
    assert result.effect == 'flow_sharing'
    assert result.candidates[0].effect == 'flow_sharing' and result.candidates[0].accepted
    assert result.candidates[0].named_by_data and result.shares['others_speed'] > 0.02
    first = result.ledger[0]
    assert first.mae_before == pytest.approx(result.mae_before)
    # The validation gap (per-record MAE) shrinks by at least 30 %.
    assert first.mae_after <= 0.7 * first.mae_before
    effect = result.model.effect('flow_sharing')
    assert isinstance(effect, FlowSharing)
    # The arm and the boom at full duty take more than the pump gives: a share below 1.
    assert effect.limit / (1.0 + 30.0 / effect.other_positive) < 0.8
    signature = result.signature
    assert signature is not None and signature.x is not None
    assert signature.feature == 'others' and signature.x.size == signature.before.size
    # The residual while the boom moves is what the effect takes away.
    busy = signature.x > 10.0
    assert np.mean(np.abs(signature.after[busy])) < np.mean(np.abs(signature.before[busy]))


def test_flow_sharing_is_not_tried_again_nor_without_another_joint_moving(
        sharing: Sharing) -> None:
    model, alone, both, result = sharing
    # A model that has the effect does not get it again.
    candidate, augmented = detector('flow_sharing').fit(
        Context(result.model, runs_of(both[:1], 0.5), 50))
    assert not candidate.applicable and augmented is None
    # The boom still: nothing to share the pump with; no other joints at all: no signal.
    candidate, _ = detector('flow_sharing').fit(Context(model, runs_of(alone[:1], 0.5), 50))
    assert not candidate.applicable and 'never move' in candidate.evidence
    # Still, read by a sensor with 0.1 deg of noise: its differentiated angle reads as
    # speed, but it travels nowhere.
    noisy = [replace(r, others=r.others + np.random.default_rng(3).normal(
        0.0, 0.1, r.others.shape)) for r in alone[:1]]
    candidate, _ = detector('flow_sharing').fit(Context(model, runs_of(noisy, 0.5), 50))
    assert not candidate.applicable and 'no other joint moves' in candidate.refused
    bare = [Record(r.t, r.v, r.y, r.joint, r.source) for r in alone[:1]]
    candidate, _ = detector('flow_sharing').fit(Context(model, runs_of(bare, 0.5), 50))
    assert not candidate.applicable and 'no other joints' in candidate.evidence


def payload_runs(arm: Machine, payload: float, seed: int) -> list[Record]:
    """Full-stroke runs of the arm at one payload, named by it."""
    return [Record(r.t, r.v, r.y, r.joint, f'{payload:g} kg {r.source}')
            for r in full_stroke_runs(with_payload(arm, payload), DT, DUTIES, seed=seed)]


@pytest.fixture(scope='module')
def payloads() -> Payloads:
    """Identify the arm without payload; return runs without and with 1200 kg."""
    arm = load_machine(shipped_config('physics_arm.yaml'))
    model = identify(payload_runs(arm, 0.0, 1), kind='sdp').model
    return arm, model, payload_runs(arm, 0.0, 50), payload_runs(arm, 1200.0, 80)


def test_without_a_load_signal_records_that_differ_are_shown_not_named(tmp_path: Path) -> None:
    # The generator's joint slowed by a valve without compensation, each record at its own
    # payload, the load not recorded: the records' speeds at the same command differ, but
    # the runs do not hold the cause, and scales of the records themselves predict no
    # other record: the finding is shown, `load_dependence` refused with what to record.
    rng = np.random.default_rng(9)
    truth, nominal = hide('load_dependence', rng, 'volt')
    loaded = []
    for index, payload in enumerate((10.0, 120.0, 50.0, 90.0)):
        # Levels of +-3, 5 and 7 V held 1-2 s, turning back before the stops.
        levels = rng.choice([3.0, 5.0, 7.0], size=25) * np.tile([1.0, -1.0], 13)[:25]
        v = np.r_[np.zeros(100), np.repeat(levels, rng.integers(100, 200, size=25))]
        load = np.full(v.size, payload)
        loaded.append(record(truth.machine, v[:, None], angles0=[np.mean(
            truth.mapping['angle_limits'])], load=load, seed=index, source=f'run {index}'))
    bare = [replace(r, load=None) for r in loaded]
    model = JointModel.from_mapping(nominal)
    # Each record's own factors hold for that record alone: judged on the records given.
    result = diagnose(bare, model, validation=bare, max_iterations=1)
    written = write_report(tmp_path, result)
    assert str(tmp_path / 'record_scales.png') in [str(path) for path in written]
    # Nothing is named: fitted to all the records at once, dead_zone and
    # angle_dependent_velocity took a third of the error each (measured) and stood in
    # for the records' difference; they wait, and say why.
    assert result.effect == 'none' and result.model == model
    candidate = result.candidates[0]
    assert candidate.effect == 'load_dependence' and not candidate.accepted
    assert 'chi2' in candidate.evidence
    assert 'no load signal' in candidate.refused and '--load-topic' in candidate.refused
    assert all('records differ in speed' in c.refused for c in result.candidates[1:]
               if c.held_out > 0.1)
    # The scales it found: lifting (positive) is slower the heavier the record's payload.
    scales = candidate.parameters['record_positive']
    payloads = [float(np.min(r.load)) for r in loaded]
    order = np.argsort(payloads)
    assert scales[order[0]] > scales[order[-1]] + 0.05


def with_pressure(arm: Machine, payload: float, runs: list[Record]) -> list[Record]:
    """Return the runs at one payload with the holding load pressure as the load, bar."""
    loaded = with_payload(arm, payload)
    actuator = Actuator(loaded.joints[0], loaded.pump)
    out = []
    for r in runs:
        # Signed: the pressure the load puts on the piston side, less the rod side's share.
        force = [actuator.geometry.load_force(actuator.geometry.extension(a)) for a in r.y]
        out.append(replace(r, load=np.array(force) / actuator.piston / 1e5))
    return out


@pytest.fixture(scope='module')
def pressures(payloads: Payloads) -> tuple[list[Record], Diagnosis]:
    """Return runs without and with 1200 kg carrying their holding pressure, diagnosed."""
    arm, model, light, heavy = payloads
    runs = with_pressure(arm, 0.0, light) + with_pressure(arm, 1200.0, heavy)
    return runs, diagnose(runs, model, max_iterations=1)


def test_an_overrunning_load_is_named_from_the_holding_pressure(
        pressures: tuple[list[Record], Diagnosis]) -> None:
    runs, result = pressures
    assert result.effect == 'load_dependence'
    candidate = result.candidates[0]
    assert candidate.effect == 'load_dependence' and candidate.accepted
    assert candidate.named_by_data and result.evidence.state == 'load'
    first = result.ledger[0]
    assert first.mae_after <= 0.7 * first.mae_before
    effect = result.model.effect('load_dependence')
    assert isinstance(effect, LoadDependence) and not effect.records

    def factor(load: float, positive: bool) -> float:
        speed = np.array([1.0 if positive else -1.0])
        model = result.model
        return float(exogenous_factor(model, speed, Exogenous(load=np.array([load])))[0])
    # The plant's ratios of the loaded to the unloaded speed at one angle: about x4.5
    # extending with the load pulling at 80-130 bar, x1.7 retracting with it pushing at
    # 80-150 bar, x1 wherever the load resists or is light (compensated flow). Whichever
    # form the data chose (the smooth factor or the overrunning root), it reads so.
    assert 3.0 < factor(-100.0, True) < 5.5
    assert 1.3 < factor(110.0, False) < 2.1
    for load in (0.0, 50.0):
        assert factor(load, True) == pytest.approx(1.0, abs=0.15)
    assert factor(0.0, False) == pytest.approx(1.0, abs=0.15)


def test_one_payload_with_its_pressure_gives_no_load_dependence(payloads: Payloads) -> None:
    arm, model, light, _ = payloads
    # The same payload twice (other noise): the load pressure moves a few bar with the angle.
    other = payload_runs(arm, 0.0, 120)
    same = with_pressure(arm, 0.0, light) + with_pressure(arm, 0.0, other)
    same = [replace(r, source=f'{r.source} {i}') for i, r in enumerate(same)]
    result = diagnose(same, model, max_iterations=1)
    candidate = next(c for c in result.candidates if c.effect == 'load_dependence')
    assert result.effect != 'load_dependence' and not candidate.accepted

"""The diagnosis names flow sharing and load dependence on the physics plant."""

from dataclasses import replace
from pathlib import Path
from typing import Sequence

from hydro_sdp.core.diagnosis import diagnose, Diagnosis
from hydro_sdp.core.identification.identify import identify
from hydro_sdp.core.model.effects import FlowSharing, LoadDependence
from hydro_sdp.core.model.exogenous_signals import load_factor
from hydro_sdp.core.model.joint_model import JointModel
from hydro_sdp.core.model.records import Record
from hydro_sdp.core.synthetic.physics.hydraulics import Actuator
from hydro_sdp.core.synthetic.physics.linkage import Geometry
from hydro_sdp.core.synthetic.physics.machine import PlantSimulator
from hydro_sdp.core.synthetic.physics.plant import Machine, with_payload
from hydro_sdp.core.synthetic.physics.runs import duty_command, full_stroke_runs
from hydro_sdp.io.documents import shipped_config
from hydro_sdp.io.plant_files import load_machine
from hydro_sdp.report.diagnosis import write_report
import numpy as np
import pytest

DT = 0.01
DUTIES = (40, 50, 60, 70, 80, 90, 100)
#: The model identified, the records with the boom still and moving, and the diagnosis.
Sharing = tuple[JointModel, list[Record], list[Record], Diagnosis]
#: The arm, the model identified without payload, and the runs at both payloads.
Payloads = tuple[Machine, JointModel, list[Record]]


def levels(machine: Machine, duration: float, moving: Sequence[int], seed: int) -> Record:
    """
    Random duties held 0.5-3 s on the joints in ``moving``, each turned back before its stops.

    Returns the first joint's record with the second joint's angle as ``others``.
    """
    rng = np.random.default_rng(seed)
    neutral = [joint.valve.neutral for joint in machine.joints]
    limits = [Geometry(joint).angle_limits for joint in machine.joints]
    sim = PlantSimulator(machine, DT, angles0=[0.5 * (low + high) for low, high in limits],
                         command_before=neutral, seed=seed)
    commands, angles = [list(neutral)], [sim.angles]
    current, left = list(neutral), [0] * len(neutral)
    while len(commands) < int(round(duration / DT)):
        for j in moving:
            if left[j] <= 0:
                low, high = limits[j]
                sign = 1.0 if rng.random() > (angles[-1][j] - low) / (high - low) else -1.0
                current[j] = duty_command(machine, j, sign * rng.uniform(35.0, 100.0))
                left[j] = int(round(rng.uniform(0.5, 3.0) / DT))
            left[j] -= 1
        commands.append(list(current))
        angles.append(sim.step(current))
    c, a = np.array(commands), np.array(angles)
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
    alone = [levels(excavator, 60.0, [0], seed) for seed in (1, 2, 3)]
    model = identify([Record(r.t, r.v, r.y, r.joint, r.source) for r in alone]).model
    both = [levels(excavator, 60.0, [0, 1], seed) for seed in (4, 5, 6)]
    return model, alone, both, diagnose(both, model)


def test_flow_sharing_is_named_first_and_the_gap_shrinks(
        sharing: Sharing, tmp_path: Path) -> None:
    model, _, both, result = sharing
    written = [str(path) for path in write_report(tmp_path, result)]
    assert str(tmp_path / 'signature.png') in written
    assert str(tmp_path / 'record_scales.png') not in written
    assert result.effect == 'flow_sharing'
    assert result.candidates[0].effect == 'flow_sharing' and result.candidates[0].significant
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


def test_a_model_with_flow_sharing_does_not_get_it_again(sharing: Sharing) -> None:
    _, _, both, result = sharing
    again = diagnose(both, result.model, max_iterations=1)
    assert again.effect != 'flow_sharing'
    candidate = next(c for c in again.candidates if c.effect == 'flow_sharing')
    assert not candidate.applicable


def test_flow_sharing_is_not_applicable_without_another_joint_moving(sharing: Sharing) -> None:
    model, alone, _, _ = sharing
    result = diagnose(alone, model, max_iterations=1)
    assert result.effect != 'flow_sharing'
    candidate = next(c for c in result.candidates if c.effect == 'flow_sharing')
    assert not candidate.applicable and 'never move' in candidate.evidence
    bare = [Record(r.t, r.v, r.y, r.joint, r.source) for r in alone]
    result = diagnose(bare, model, max_iterations=1)
    candidate = next(c for c in result.candidates if c.effect == 'flow_sharing')
    assert not candidate.applicable and 'no other joints' in candidate.evidence


def payload_runs(arm: Machine, payload: float, seed: int) -> list[Record]:
    """Full-stroke runs of the arm at one payload, named by it."""
    return [Record(r.t, r.v, r.y, r.joint, f'{payload:g} kg {r.source}')
            for r in full_stroke_runs(with_payload(arm, payload), DT, DUTIES, seed=seed)]


@pytest.fixture(scope='module')
def payloads() -> Payloads:
    """Identify the arm without payload; return runs without and with 1200 kg."""
    arm = load_machine(shipped_config('physics_arm.yaml'))
    model = identify(payload_runs(arm, 0.0, 1), kind='power_sat').model
    return arm, model, payload_runs(arm, 0.0, 50) + payload_runs(arm, 1200.0, 80)


def test_load_dependence_is_named_first_from_per_record_scales(
        payloads: Payloads, tmp_path: Path) -> None:
    _, model, runs = payloads
    result = diagnose(runs, model, max_iterations=1)
    written = write_report(tmp_path, result)
    assert str(tmp_path / 'record_scales.png') in [str(path) for path in written]
    assert result.effect == 'load_dependence'
    candidate = result.candidates[0]
    assert candidate.effect == 'load_dependence' and 'chi2' in candidate.evidence
    first = result.ledger[0]
    assert first.mae_after <= 0.7 * first.mae_before
    effect = result.model.effect('load_dependence')
    assert isinstance(effect, LoadDependence)
    # The payload speeds up the arm moving with gravity (positive duty), a few tenths at
    # the lower duties; the records without payload keep factors near 1.
    heavy = [up for key, up in zip(effect.records, effect.record_positive)
             if key.startswith('1200 kg full stroke +4')]
    light = [up for key, up in zip(effect.records, effect.record_positive)
             if key.startswith('0 kg full stroke +4')]
    assert heavy[0] > 1.2 and abs(light[0] - 1.0) < 0.1
    again = diagnose(runs, result.model, max_iterations=1)
    assert again.effect != 'load_dependence'


def test_one_payload_gives_no_load_dependence(payloads: Payloads) -> None:
    arm, model, runs = payloads
    # The same payload twice (other noise): the records' scales agree within their noise.
    same = runs[:len(DUTIES) * 2] + payload_runs(arm, 0.0, 120)
    same = [replace(r, source=f'{r.source} {i}') for i, r in enumerate(same)]
    result = diagnose(same, model, max_iterations=1)
    candidate = next(c for c in result.candidates if c.effect == 'load_dependence')
    assert result.effect != 'load_dependence' and not candidate.significant
    assert 'within noise' in candidate.evidence


def pressure_runs(arm: Machine, payload: float, seed: int) -> list[Record]:
    """Full-stroke runs at one payload with the holding load pressure as the load, bar."""
    loaded = with_payload(arm, payload)
    actuator = Actuator(loaded.joints[0], loaded.pump)
    out = []
    for r in payload_runs(arm, payload, seed):
        # Signed: the pressure the load puts on the piston side, less the rod side's share.
        force = [actuator.geometry.load_force(actuator.geometry.extension(a)) for a in r.y]
        out.append(replace(r, load=np.array(force) / actuator.piston / 1e5))
    return out


@pytest.fixture(scope='module')
def pressures(payloads: Payloads) -> tuple[list[Record], Diagnosis]:
    """Return runs without and with 1200 kg carrying their holding pressure, diagnosed."""
    arm, model, _ = payloads
    runs = pressure_runs(arm, 0.0, 50) + pressure_runs(arm, 1200.0, 80)
    return runs, diagnose(runs, model, max_iterations=1)


def test_an_overrunning_load_is_named_first_from_the_holding_pressure(
        pressures: tuple[list[Record], Diagnosis]) -> None:
    runs, result = pressures
    assert result.effect == 'load_dependence'
    candidate = result.candidates[0]
    assert candidate.effect == 'load_dependence' and candidate.significant
    assert 'overrunning' in candidate.evidence
    first = result.ledger[0]
    assert first.mae_after <= 0.7 * first.mae_before
    effect = result.model.effect('load_dependence')
    assert isinstance(effect, LoadDependence)
    assert effect.positive == effect.negative == 0.0 and not effect.records

    def factor(load: float, positive: bool) -> float:
        if positive:
            return float(load_factor(np.array([load]), 0.0, 0.0, effect.overrun_positive,
                                     effect.onset_positive)[0])
        return float(load_factor(np.array([load]), 0.0, 0.0, effect.overrun_negative,
                                 effect.onset_negative)[0])
    # The plant's ratios of the loaded to the unloaded speed at one angle: x4.5 extending
    # with the load pulling at 80-130 bar, x1.7 retracting with it pushing at 80-150 bar,
    # x1 wherever the load resists or is light (compensated flow).
    assert 3.8 < factor(-100.0, True) < 5.0
    assert 1.5 < factor(110.0, False) < 1.9
    for load in (0.0, 50.0, 120.0):
        assert factor(load, True) == pytest.approx(1.0)
    for load in (-100.0, 0.0):
        assert factor(load, False) == pytest.approx(1.0)
    again = diagnose(runs, result.model, max_iterations=1)
    assert again.effect == 'none'
    candidate = next(c for c in again.candidates if c.effect == 'load_dependence')
    assert not candidate.significant


def test_one_payload_with_its_pressure_gives_no_load_dependence(payloads: Payloads) -> None:
    arm, model, _ = payloads
    # The same payload twice (other noise): the load pressure moves a few bar with the angle.
    same = pressure_runs(arm, 0.0, 50) + pressure_runs(arm, 0.0, 120)
    same = [replace(r, source=f'{r.source} {i}') for i, r in enumerate(same)]
    result = diagnose(same, model, max_iterations=1)
    candidate = next(c for c in result.candidates if c.effect == 'load_dependence')
    assert result.effect != 'load_dependence' and not candidate.significant

"""The link ringing on the oil column: named on the generator, its frequency the plant's."""

from dataclasses import replace

from hydro_sdp.core.diagnosis.context import Context
from hydro_sdp.core.diagnosis.detectors import detector
from hydro_sdp.core.diagnosis.detectors.dynamics import LINE, spectral_line
from hydro_sdp.core.diagnosis.residuals import runs_of
from hydro_sdp.core.model.effects import DirectionDependentDelay
from hydro_sdp.core.synthetic.physics.hydraulics import Actuator
from hydro_sdp.core.synthetic.physics.oil_column import OilColumn
from hydro_sdp.io.documents import shipped_config
from hydro_sdp.io.plant_files import load_machine
import numpy as np
import pytest
from support.diagnosis_grid import make_case, run_case
from support.plant_grid import _identify
from support.plant_programs import levels

pytestmark = pytest.mark.slow(15)


def test_a_ringing_joint_of_the_generator_is_named_and_its_mode_found():
    # Full strokes from stop to stop: the link swings past the stop the sensor reads.
    case = make_case('oscillation', 'stroke', 'signed_percent', 0, seconds=30.0)
    result = run_case(case, max_iterations=2)
    assert result.named == 'oscillation' and result.mae_after <= 0.5 * result.mae_before, \
        result


@pytest.mark.parametrize('kind, units', [('stroke', 'volt'), ('random', 'percent')])
def test_split_dead_times_that_took_the_links_lag_are_shortened_together(kind, units):
    # A direction-dependent delay identified on ringing data holds the link's lag in both
    # directions: the mode is fitted with both shortened by the same whole samples (kept
    # as they were, the fit moved 1-10 % off the frequency).
    case = make_case('oscillation', kind, units, 0, seconds=30.0)
    true_delay = case.model.delay
    frequency, damping = case.truth.joint.mode
    split = case.model.with_effect(DirectionDependentDelay(true_delay + 0.03, true_delay + 0.03))
    candidate, augmented = detector('oscillation').fit(
        Context(split, runs_of(list(case.estimation), 0.5), 50))
    assert augmented is not None and candidate.significant
    found = candidate.parameters
    assert abs(found['frequency'] / frequency - 1.0) < 0.03
    assert abs(found['damping'] - damping) < 0.01
    assert found['positive'] == found['negative']
    assert true_delay - 0.005 < found['positive'] < true_delay + 0.015
    assert augmented.effect(DirectionDependentDelay.name).positive == found['positive']


def test_a_lag_taken_for_a_damped_mode_is_shown_as_looked_for_and_not_found():
    # A missing valve lag fits a mode damped at 0.6: no ring and no line, and the report
    # lists the word with its evidence (it was tried on these runs).
    case = make_case('valve_lag', 'random', 'volt', 0, seconds=30.0)
    candidate, augmented = detector('oscillation').fit(
        Context(case.model, runs_of(list(case.estimation), 0.5), 50))
    assert augmented is None and candidate.applicable and not candidate.accepted
    assert 'does not ring' in candidate.evidence and 'spectrum' not in candidate.evidence


def test_on_the_physics_plant_the_fitted_mode_is_the_oil_columns():
    # The model of the boom identified with its pressures settled at every sample, held
    # against random levels of the same boom on its soft oil column (1.95-2.17 Hz over the
    # stroke by Merritt's formula, damped 0.09-0.12 by the seals' viscous friction, more by
    # the orifices and the Coulomb friction).
    ringing = load_machine(shipped_config('physics_boom_compressible.yaml'))
    settled = replace(ringing, joints=(replace(ringing.joints[0], compressibility=None),))
    model = _identify(settled, [levels(settled, 20.0, k) for k in range(2)], 'power_sat')
    records = [levels(ringing, 20.0, 10 + k) for k in range(2)]
    candidate, augmented = detector('oscillation').fit(Context(model, runs_of(records, 0.5), 50))
    joint = ringing.joints[0]
    column = OilColumn(joint, Actuator(joint, ringing.pump), 0.0)
    stroke = Actuator(joint, ringing.pump).stroke
    formula = [column.natural_frequency(s) for s in np.linspace(0.0, stroke, 11)]
    assert 0.97 * min(formula) < candidate.parameters['frequency'] < 1.03 * max(formula)
    assert 0.09 < candidate.parameters['damping'] < 0.3
    assert candidate.significant and candidate.gain > 0.2 and augmented is not None


def test_a_ring_in_the_residual_stands_as_a_line_and_noise_does_not():
    # 40 s of white residual, and the same with a 2 Hz ring dying out after every
    # change, 3 to 5 s apart (as a joint's starts and stops).
    dt, rng = 0.01, np.random.default_rng(3)
    noise = [rng.normal(0.0, 0.02, 4000) for _ in range(2)]
    t = np.arange(300) * dt
    burst = 0.1 * np.exp(-0.12 * 2 * np.pi * 2.0 * t) * np.sin(2 * np.pi * 2.0 * t)
    ringing = []
    for residual in noise:
        residual = residual.copy()
        for start in np.cumsum(rng.uniform(300, 500, 12)).astype(int):
            if start + burst.size <= residual.size:
                residual[start:start + burst.size] += burst * rng.choice([-1.0, 1.0])
        ringing.append(residual)
    frequency, times = spectral_line(ringing, dt, 15.0)
    assert abs(frequency - 2.0) <= 0.125 and times >= LINE
    assert spectral_line(noise, dt, 15.0)[1] < 0.6 * LINE
    assert np.isnan(spectral_line([noise[0][:500]], dt, 15.0)[1])

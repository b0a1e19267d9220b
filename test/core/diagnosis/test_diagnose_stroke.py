"""The word stroke_geometry: a speed factor of the angle shared by both directions."""

from hydro_sdp.core.diagnosis import diagnose, runs_of
from hydro_sdp.core.diagnosis.context import Context
from hydro_sdp.core.diagnosis.detectors import detector
from hydro_sdp.core.diagnosis.detectors.stroke_shape import factor_parts, stroke_samples
from hydro_sdp.core.identification.identify import identify
from hydro_sdp.core.synthetic.physics.plant import with_payload
from hydro_sdp.core.synthetic.physics.runs import full_stroke_runs, random_levels
from hydro_sdp.io.documents import shipped_config
from hydro_sdp.io.plant_files import load_machine
from hydro_sdp.plots import plot_signature
import numpy as np
import pytest
from support.diagnosis_grid import make_case, run_case

pytestmark = [pytest.mark.usefixtures('figures_not_drawn')]


def context_of(case):
    return Context(case.model, runs_of(case.estimation, 0.5), 50)


@pytest.fixture(scope='module')
def stroked():
    """Return full strokes of a generator joint with a linkage factor the model lacks."""
    return make_case('stroke_geometry', 'stroke', 'signed_percent', 0, seconds=40.0)


def test_a_shared_factor_is_fitted_where_it_is_and_not_where_the_factor_is_opposite(stroked):
    case = stroked
    truth = case.truth.model.effect('stroke_geometry')
    context = context_of(case)
    parts = factor_parts(stroke_samples(context))
    # Beyond the map and the transients, the shared factor explains the residual, the
    # opposite one far less.
    assert parts.signature
    assert parts.command - parts.shared > 3.0 * (parts.command - parts.opposite)
    found, augmented = detector('stroke_geometry').fit(context)
    assert found.significant and found.signature_match and found.gain > 0.5
    geometry = augmented.effect('stroke_geometry')
    # Inside the stroke (away from the cushions) the factor is the true one, both ways.
    low, high = case.truth.model.angle_limits
    angles = np.linspace(low + 0.15 * (high - low), high - 0.15 * (high - low), 9)
    for sign in (1.0, -1.0):
        want = truth.factor(angles, np.full(9, sign))
        np.testing.assert_allclose(geometry.factor(angles, np.full(9, sign)), want, rtol=0.1)
    # A gravity-like factor (opposite for the two directions) is not this word's.
    gravity = make_case('angle_dependent_velocity', 'stroke', 'signed_percent', 0,
                        seconds=40.0)
    context = context_of(gravity)
    parts = factor_parts(stroke_samples(context))
    assert not parts.signature
    assert parts.command - parts.opposite > parts.command - parts.shared
    found, augmented = detector('stroke_geometry').fit(context)
    assert augmented is None and not found.significant
    assert 'not change along the stroke alike' in found.evidence


@pytest.mark.slow
@pytest.mark.parametrize('word, kind, units', [
    ('angle_dependent_velocity', 'stroke', 'signed_percent')])
def test_shared_and_opposite_angle_factors_are_told_apart(word, kind, units):
    result = run_case(make_case(word, kind, units, 0, seconds=40.0), max_iterations=2)
    assert result.named == word, result
    assert result.mae_after <= 0.5 * result.mae_before


def test_the_signature_draws_each_direction_along_its_motion(stroked):
    case = stroked
    context = context_of(case)
    _, augmented = detector('stroke_geometry').fit(context)
    run = context.runs[0]
    signature = detector('stroke_geometry').signature(case.model, augmented, run)
    assert signature.feature == 'angle' and signature.signs.size == signature.x.size
    assert set(np.unique(signature.signs)) <= {-1.0, 0.0, 1.0}
    ax, = plot_signature(signature).axes
    labels = [line.get_label() for line in ax.get_lines()]
    assert labels[:4] == ['before, moving up', 'before, moving down', 'after, moving up',
                          'after, moving down']
    assert ax.get_ylabel() == 'mean residual along the motion (deg/s)'
    # Signed by the motion, the shared factor shows as one curve in both directions.
    up, down = ax.get_lines()[:2]
    common, mine, theirs = np.intersect1d(up.get_xdata(), down.get_xdata(),
                                          return_indices=True)
    assert common.size > 10
    assert np.corrcoef(up.get_ydata()[mine], down.get_ydata()[theirs])[0, 1] > 0.8
    after = np.r_[ax.get_lines()[2].get_ydata(), ax.get_lines()[3].get_ydata()]
    assert np.mean(np.abs(after)) < 0.3 * np.mean(np.abs(
        np.r_[up.get_ydata(), down.get_ydata()]))


#: Load on the arm and on the boom while estimating, kg.
PAYLOAD = {'arm': 250.0, 'boom': 600.0}


@pytest.fixture(scope='module', params=['boom'])
def plant(request):
    """Full-stroke runs, the model identified from them, and held-out random levels."""
    machine = with_payload(load_machine(shipped_config(f'physics_{request.param}.yaml')),
                           PAYLOAD[request.param])
    runs = full_stroke_runs(machine, 0.01, (40, 70, 100), seed=11)
    held_out = [random_levels(machine, 0.01, 30.0, seed=1)]
    # The family identify chooses for these runs (auto), named to skip the choice.
    return runs, identify(runs, kind='power_sat').model, held_out


@pytest.mark.slow
def test_the_linkage_of_the_physics_plant_is_named_and_the_gap_shrinks(plant):
    runs, model, held_out = plant
    assert model.effect('stroke_geometry') is not None
    full = diagnose(runs, model, validation=held_out, max_iterations=1)
    assert full.effect == 'none' and full.mae_after == full.mae_before
    without = model.without_effect('stroke_geometry')
    result = diagnose(runs, without, validation=held_out, max_iterations=1)
    assert result.effect == 'stroke_geometry' == result.candidates[0].effect
    assert result.candidates[0].signature_match
    assert result.mae_after <= 0.7 * result.mae_before
    # Each full-stroke run moves one way; the signature spans runs, so it shows both.
    moving = result.signature.signs[result.signature.signs != 0.0]
    assert {-1.0, 1.0} <= set(np.unique(moving))
    assert result.signature.x.size == result.signature.before.size


def test_the_report_shows_the_residual_against_the_angle_per_direction(stroked, tmp_path):
    from hydro_sdp.report.diagnosis import write_report
    case = stroked
    result = diagnose(case.estimation, case.model, validation=case.validation,
                      max_iterations=1)
    assert result.effect == 'stroke_geometry'
    assert result.mae_after <= 0.5 * result.mae_before
    assert result.signature.signs.size == result.signature.x.size
    written = write_report(tmp_path, result)
    assert str(tmp_path / 'signature.png') in written
    summary = (tmp_path / 'summary.md').read_text()
    assert 'for each direction of motion apart, signed by the motion' in summary
    assert summary.index('for each direction') < summary.index('![signature](signature.png)')

"""Identification with known answers: dead time and lag, map families, methods, step-and-return."""

from hydro_sdp.core.identification.evaluation import mean_errors, record_mae, RecordScore
from hydro_sdp.core.identification.identify import identify
from hydro_sdp.core.identification.map_fit import pwl_layout
from hydro_sdp.core.model.effects import StrokeGeometry, ValveLag
from hydro_sdp.core.model.joint_model import JointModel
from hydro_sdp.core.model.records import Record
from hydro_sdp.core.model.simulation import simulate
from hydro_sdp.core.model.static_maps import PolyMap, PowerSatMap, SdpMap
import numpy as np
import pytest

pytestmark = [pytest.mark.slow]

CONVEX = PowerSatMap((-37.5, 37.5), (-40.0, 32.0), (0.03, 0.035), (3.0, 2.5))


def full_strokes(truth, duties, *, low, high, noise=0.002, seed=1, rest=0.0, scale=1.0):
    """Constant-duty runs from one stop to the other and on against it, both directions."""
    rng = np.random.default_rng(seed)
    records = []
    for sign, start in ((1.0, low), (-1.0, high)):
        for duty in duties:
            command = rest + scale * sign * duty
            speed = max(abs(float(truth.rate(command))), 1.0)
            samples = int((high - low) / speed / 0.01) + 150
            v = np.r_[np.full(100, rest), np.full(samples, command)]
            y = simulate(truth, v, 0.01, start, v_before=rest) + rng.normal(0.0, noise, v.size)
            records.append(Record(np.arange(1, v.size + 1) * 0.01, v, y, 'j',
                                  f'run {sign * duty:+g}'))
    return records


def test_dead_time_and_valve_lag_are_found_together():
    truth = JointModel('j', CONVEX, 0.25, angle_limits=(-40.0, 50.0), effects=(ValveLag(0.1),))
    result = identify(full_strokes(truth, (45, 55, 65, 80, 100), low=-40.0, high=50.0))
    assert result.delay.samples == 25
    assert result.delay.lag == pytest.approx(0.1, abs=0.01)
    assert abs(result.delay.onset - 25) <= 1 and abs(result.delay.xcorr - 25) <= 1
    model = result.model
    lag = model.effect('valve_lag')
    assert isinstance(lag, ValveLag) and lag.time_constant == pytest.approx(0.1, abs=0.01)
    # The convex valve: eq. (5) loses, the saturating power law is found with its exponents.
    assert model.kind == 'power_sat'
    np.testing.assert_allclose(model.static_map.exponent, (3.0, 2.5), rtol=0.02)
    np.testing.assert_allclose(model.dead_zone, (-37.5, 37.5), atol=0.2)
    assert model.angle_limits == pytest.approx((-40.0, 50.0), abs=0.05)


def test_a_level_that_creeps_just_beyond_the_edge_bounds_it():
    # At +-45 the convex valve moves the joint at 1.1 and 0.45 deg/s, 1-3 % of its full
    # speed, for a whole 90 s stroke: the edge must lie inside that level.
    truth = JointModel('j', CONVEX, 0.2, angle_limits=(-40.0, 50.0))
    assert 0.0 < -float(truth.rate(-45.0)) < 0.02 * 40.0
    records = full_strokes(truth, (45, 60, 80, 100), low=-40.0, high=50.0)
    model = identify(records, kind='power_sat').model
    np.testing.assert_allclose(model.dead_zone, CONVEX.dead_zone, atol=0.1)
    np.testing.assert_allclose(model.static_map.exponent, CONVEX.exponent, rtol=0.02)
    slowest = [record for record in records if abs(record.v[-1]) == 45.0]
    assert max(record_mae(model, record) for record in slowest) < 0.05


def test_pwl_puts_a_knot_at_every_measured_level():
    levels = np.array([-100.0, -80.0, -60.0, -40.0, 0.0, 40.0, 50.0, 60.0, 70.0, 100.0])
    layout = pwl_layout(levels, (-37.5, 37.5))
    np.testing.assert_array_equal(layout.knots, [-100, -80, -60, -40, -37.5, 37.5, 40, 50, 60,
                                                 70, 100])
    many = np.linspace(1.0, 10.0, 40)
    assert pwl_layout(np.r_[-many, many], (-0.5, 0.5)).positive == 12


@pytest.mark.parametrize('kind', ['pwl', 'poly', 'power_sat', 'sdp'])
def test_output_error_is_honoured_by_every_family(kind):
    truth = JointModel('j', CONVEX, 0.2, angle_limits=(-40.0, 50.0))
    result = identify(full_strokes(truth, (45, 60, 80, 100), low=-40.0, high=50.0),
                      method='oe', kind=kind)
    assert result.fit.method == 'oe' and result.fit.beta == 0.0
    assert result.model.kind == kind


def test_poly_on_a_valve_that_rests_at_50():
    truth = JointModel('duty', SdpMap((30.0, 68.0), (-20.0, 25.0), (0.08, 0.07)), 0.1,
                       angle_limits=(-30.0, 60.0), input_limits=(0.0, 100.0))
    records = full_strokes(truth, (25, 30, 40, 50), low=-30.0, high=60.0, rest=49.0)
    result = identify(records, kind='poly', input_limits=(0.0, 100.0), rest=49.0)
    static_map = result.model.static_map
    assert isinstance(static_map, PolyMap) and static_map.rest == 49.0
    levels = np.array([0.0, 9.0, 19.0, 79.0, 89.0, 99.0])
    np.testing.assert_allclose(static_map.rate(levels), truth.rate(levels), rtol=0.05, atol=0.5)
    assert PolyMap.from_mapping(static_map.to_mapping()) == static_map


def step_and_return_record(truth, levels, back, *, seed=0):
    """Return steps from a home angle, each followed by a return at one fixed command."""
    rng = np.random.default_rng(seed)
    v = []
    home = 20.0
    angle = home
    for level in levels:
        block = np.r_[np.zeros(100), np.full(150, level), np.zeros(100)]
        y = simulate(truth, block, 0.01, angle)
        sign = 1.0 if y[-1] < home else -1.0
        speed = abs(float(truth.rate(sign * back)))
        samples = int(abs(y[-1] - home) / speed / 0.01) + 1
        v.append(np.r_[block, np.full(samples, sign * back)])
        angle = float(simulate(truth, v[-1], 0.01, angle)[-1])
    v = np.concatenate(v + [np.zeros(100)])
    y = simulate(truth, v, 0.01, home) + rng.normal(0.0, 0.02, v.size)
    return Record(np.arange(1, v.size + 1) * 0.01, v, y, 'j', 'step and return')


def test_a_simulated_sdp_joint_with_return_moves_is_identified_as_sdp():
    truth = JointModel('j', SdpMap((-1.1, 1.52), (-25.0, 42.0), (1.2, 2.1)), 0.12,
                       angle_limits=(-60.0, 100.0))
    levels = [2.0, -2.0, 3.0, -3.0, 4.0, -4.0, 5.5, -5.5, 7.0, -7.0, 9.0, -9.0]
    result = identify([step_and_return_record(truth, levels, 6.0)])
    assert result.segmentation.rest == 0.0
    assert result.model.kind == 'sdp'
    np.testing.assert_allclose(result.model.dead_zone, (-1.1, 1.52), atol=0.03)
    np.testing.assert_allclose(result.model.static_map.saturation_velocity, (-25.0, 42.0),
                               rtol=0.03)


def test_stroke_geometry_is_recovered_from_full_strokes():
    geometry = StrokeGeometry(knots=(-40.0, -30.0, 0.0, 40.0, 50.0),
                              factors=(0.7, 0.7, 1.3, 0.8, 0.8))
    truth = JointModel('j', CONVEX, 0.2, angle_limits=(-40.0, 50.0), effects=(geometry,))
    result = identify(full_strokes(truth, (45, 55, 65, 80, 100), low=-40.0, high=50.0),
                      kind='power_sat')
    found = result.model.effect('stroke_geometry')
    assert isinstance(found, StrokeGeometry)
    # Inside the stroke (where each run starts, the joint is still speeding up through
    # the delay and the lag) the shape is recovered; the scale is the map's.
    angles = np.linspace(-30.0, 40.0, 8)
    shape = found.factor(angles, np.ones(8))
    want = geometry.factor(angles, np.ones(8))
    np.testing.assert_allclose(shape / np.mean(shape), want / np.mean(want), rtol=0.05)
    assert result.mae < 0.1


def test_evaluate_averages_per_record_and_over_time():
    scores = [RecordScore('a', 100, 1.0, 2.0, 3.0, 0.5), RecordScore('b', 300, 3.0, 2.0, 1.0, 0.5)]
    means = mean_errors(scores)
    assert means['per_record'] == {'model': 2.0, 'sdp_dz': 2.0, 'linear': 2.0}
    assert means['time_weighted'] == {'model': 2.5, 'sdp_dz': 2.0, 'linear': 1.5}

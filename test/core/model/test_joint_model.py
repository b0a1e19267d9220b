"""The joint model: the paper's numbers, validation and model-file round trips."""

import math
from typing import get_args

from hydro_sdp.core.control.idz import idz_mode, IDZ_MODES, InverseDeadZone
from hydro_sdp.core.errors import ConfigurationError, ModelFileError
from hydro_sdp.core.model.effects import (
    AngleDependentVelocity, Backlash, DirectionDependentDelay, effect_from_mapping, StrokeGeometry,
    ValveLag)
from hydro_sdp.core.model.joint_model import delay_samples, JointModel
from hydro_sdp.core.model.static_maps import (
    chord_commands, linearise, LinearMap, MAP_KINDS, MapKind, PolyMap, PowerSatMap, PwlMap,
    sdp_rate, SdpDzMap, SdpMap, shifted_map)
from hydro_sdp.core.validation import require_float_list
from hydro_sdp.io.model_files import dump_model, load_model, save_model
import numpy as np
import pytest
import yaml

J2_ALPHA = (-0.2951, 1.3560, -1.3298, 0.3887, 1.7710, 1.3124)


def test_j2_rates_match_methods_section_3_1(j2):
    rates = j2.rate(np.array([-2.2, 1.75]))
    assert rates[0] == pytest.approx(-20.442, abs=5e-4)
    assert rates[1] == pytest.approx(20.962, abs=5e-4)
    # q(v)/dt at dt = 0.01 s is the same number as the rate.
    q = SdpMap.from_alpha(J2_ALPHA, 0.01).rate(np.array([-2.2, 1.75])) * 0.01
    np.testing.assert_allclose(q / 0.01, rates, rtol=1e-12)


def test_j2_saturation_and_dead_zone(j2):
    far = j2.rate(np.array([-1e3, 1e3]))
    np.testing.assert_allclose(far, [-29.51, 38.87], rtol=1e-12)
    inside = j2.rate(np.linspace(-1.3298, 1.3124, 51))
    assert np.all(inside == 0.0)
    # 97-99 % of saturation at 4-5 V, as the paper says.
    assert j2.rate(np.array([-4.0]))[0] / -29.51 == pytest.approx(0.973, abs=1e-3)
    assert j2.rate(np.array([5.0]))[0] / 38.87 == pytest.approx(0.999, abs=1e-3)


def test_alpha_is_the_papers_form(j2):
    np.testing.assert_allclose(j2.alpha(0.01), J2_ALPHA, rtol=1e-12)
    alpha_05 = j2.alpha(0.05)
    assert alpha_05[0] == pytest.approx(5 * J2_ALPHA[0])
    assert alpha_05[3] == pytest.approx(5 * J2_ALPHA[3])
    assert alpha_05[1:3] == pytest.approx(J2_ALPHA[1:3])


def test_alpha_needs_kind_sdp(j2):
    dz = JointModel('j', SdpDzMap((-1.0, 1.0), (20.0, 30.0)), 0.1)
    with pytest.raises(ConfigurationError, match='kind sdp'):
        dz.alpha(0.01)


@pytest.mark.parametrize(('dt', 'samples'), [(0.01, 15), (0.05, 3), (0.1, 2), (0.15, 1), (1.0, 1)])
def test_delay_in_samples(j2, dt, samples):
    assert j2.delay_samples(dt) == samples


def test_delay_is_at_least_one_sample():
    # A command issued at t_k moves the joint in the interval ending at t_{k+1} at the earliest.
    assert delay_samples(0.0, 0.01) == 1
    assert delay_samples(0.004, 0.01) == 1


def test_delay_rejects_bad_period(j2):
    with pytest.raises(ConfigurationError, match='sample period'):
        j2.delay_samples(0.0)
    with pytest.raises(ConfigurationError, match='sample period'):
        j2.longest_delay_samples(math.nan)


def test_idz_slopes_at_the_control_period(j2):
    chord = linearise(j2.static_map, -2.2, 1.75)
    assert chord.slope[0] == pytest.approx(23.49, abs=5e-3)
    assert chord.slope[1] == pytest.approx(47.90, abs=5e-3)
    # docs/methods.md section 3.3: per 0.05 s control sample.
    assert chord.slope[0] * 0.05 == pytest.approx(1.1746, abs=1e-4)
    assert chord.slope[1] * 0.05 == pytest.approx(2.3951, abs=1e-4)
    np.testing.assert_allclose(chord.rate(np.array([-2.2, 1.75])),
                               j2.rate(np.array([-2.2, 1.75])), rtol=1e-12)


def test_linear_and_dead_zone_maps():
    linear = LinearMap(12.0)
    np.testing.assert_allclose(linear.rate(np.array([-2.0, 0.0, 0.5])), [-24.0, 0.0, 6.0])
    dz = SdpDzMap((-1.0, 2.0), (10.0, 20.0))
    np.testing.assert_allclose(dz.rate(np.array([-3.0, -1.0, 0.0, 2.0, 2.5])),
                               [-20.0, 0.0, 0.0, 0.0, 10.0])


def _model_with_everything():
    return JointModel(
        'boom', SdpMap((-1.234567890123, 0.98765432101), (-31.123456789, 44.5), (1.1, 2.2)),
        delay=0.123456789, angle_limits=(-20.5, 70.25), input_limits=(-10.0, 10.0),
        effects=(Backlash(0.7), ValveLag(0.0833333333333), AngleDependentVelocity(0.3, 12.5),
                 DirectionDependentDelay(0.1, 0.25)))


def test_model_file_round_trip_is_exact(tmp_path, j2):
    for model in (j2, _model_with_everything(),
                  JointModel('dipper', LinearMap(12.000000000000002), 0.1),
                  JointModel('stick', SdpDzMap((-5.5, 12.25), (0.3, 0.45)), 0.2,
                             input_limits=(-100.0, 100.0))):
        path = save_model(model, tmp_path / f'{model.joint}.yaml')
        loaded = load_model(path)
        assert loaded == model
        assert dump_model(loaded) == path.read_text()


def test_effects_keep_a_canonical_order():
    a = JointModel('j', LinearMap(1.0), 0.0, effects=(Backlash(0.1), ValveLag(0.2)))
    b = JointModel('j', LinearMap(1.0), 0.0, effects=(ValveLag(0.2), Backlash(0.1)))
    assert a == b
    assert a.with_effect(Backlash(0.3)).effect('backlash') == Backlash(0.3)
    assert a.without_effect('valve_lag').effect('valve_lag') is None


def test_shipped_model_is_the_j2_of_the_paper(j2):
    assert j2.joint == 'j2'
    assert j2.kind == 'sdp'
    assert j2.delay == 0.15
    assert j2.angle_limits == (-13.8, 63.6)
    assert j2.dead_zone == (-1.3298, 1.3124)


def _base():
    return yaml.safe_load(dump_model(_model_with_everything()))


def _without(key):
    data = _base()
    del data[key]
    return data


def _with(**changes):
    data = _base()
    data.update(changes)
    return data


BAD_MAPPINGS = [
    (_without('joint'), "missing required key 'joint'"),
    (_without('delay'), "missing required key 'delay'"),
    (_without('curvature'), "missing required key 'curvature' for kind 'sdp'"),
    (_with(speed=3), "unknown key 'speed'"),
    (_with(format='hydro_sdp/model/v0'), "key 'format'"),
    (_with(kind='cubic'), "key 'kind'"),
    (_with(gain=3.0), "key 'gain' does not apply to kind 'sdp'"),
    (_with(delay='fast'), "key 'delay': expected a number"),
    (_with(delay=True), "key 'delay': expected a number"),
    (_with(delay=float('nan')), "key 'delay': must be finite"),
    (_with(delay=-0.1), "key 'delay'"),
    (_with(joint=''), "key 'joint'"),
    (_with(dead_zone=[1.0, -1.0]), "key 'dead_zone'"),
    (_with(dead_zone=[-1.0]), "key 'dead_zone'"),
    (_with(dead_zone=[-20.0, 1.0]), "key 'dead_zone'.*outside input_limits"),
    (_with(angle_limits=[60.0, -10.0]), "key 'angle_limits'"),
    (_with(angle_limits=[5.0, 5.0]), "key 'angle_limits'"),
    (_with(input_limits=[10.0, -10.0]), "key 'input_limits'"),
    (_with(saturation_velocity=[30.0, 40.0]), "key 'saturation_velocity'"),
    (_with(curvature=[0.0, 1.0]), "key 'curvature'"),
    (_with(curvature=[1.0, float('inf')]), r"key 'curvature\[1\]': must be finite"),
    (_with(effects={'stiction': {}}), "unknown effect 'stiction'"),
    (_with(effects={'valve_lag': {}}), "missing parameter 'time_constant'"),
    (_with(effects={'valve_lag': {'time_constant': -1.0}}), 'time_constant'),
    (_with(effects={'valve_lag': {'tau': 1.0}}), "unknown parameter 'tau'"),
    (_with(effects={'backlash': 0.5}), "key 'effects.backlash'"),
    (_with(effects=[1, 2]), "key 'effects'"),
    (_with(effects={'angle_dependent_velocity': {'amplitude': 1.5}}), 'amplitude'),
    (_with(effects={'direction_dependent_delay': {'positive': 0.1, 'negative': -1.0}}),
     'negative'),
    ([1, 2, 3], 'must be a mapping'),
]


@pytest.mark.parametrize(('data', 'message'), BAD_MAPPINGS)
def test_bad_model_mappings_are_refused_with_the_key(data, message):
    with pytest.raises(ModelFileError, match=message):
        JointModel.from_mapping(data)


@pytest.mark.parametrize(('content', 'message'), [
    ('', 'file is empty'),
    ('   \n', 'file is empty'),
    ('kind: [sdp\n', 'not valid YAML at line'),
    ('!!python/object/apply:os.system ["true"]\n', 'not valid YAML'),
    ('just a string\n', 'must be a mapping'),
])
def test_bad_model_files_are_refused(tmp_path, content, message):
    path = tmp_path / 'model.yaml'
    path.write_text(content)
    with pytest.raises(ModelFileError, match=message):
        load_model(path)


def test_model_file_that_is_a_directory_or_missing(tmp_path):
    with pytest.raises(ModelFileError, match='is a directory'):
        load_model(tmp_path)
    with pytest.raises(ModelFileError, match='no such file'):
        load_model(tmp_path / 'absent.yaml')


EXAMPLE_MAPS = (
    SdpMap((-1.3298, 1.3124), (-29.51, 38.87), (1.356, 1.771)),
    SdpDzMap((-1.0, 2.0), (10.0, 20.0)),
    LinearMap(12.0),
    PwlMap((-8.0, -1.0, 1.5, 8.0), (-30.0, 0.0, 0.0, 30.0)),
    PolyMap((2.0, 0.1), (3.0,), (-5.0, 5.0)),
    PowerSatMap((-37.5, 37.5), (-40.0, 32.0), (0.03, 0.04), (3.0, 2.5)),
)


def test_every_kind_is_registered_once_and_round_trips():
    assert tuple(MAP_KINDS) == get_args(MapKind)
    assert [m.kind for m in EXAMPLE_MAPS] == list(MAP_KINDS)
    for static_map in EXAMPLE_MAPS:
        cls = MAP_KINDS[static_map.kind]
        assert type(static_map) is cls
        assert set(static_map.to_mapping()) == set(cls.keys)
        assert cls.from_mapping(static_map.to_mapping()) == static_map


def test_sdp_equation_in_rates_and_in_the_papers_alpha(j2):
    v = np.array([-1e3, -2.2, -1.3298, 0.0, 1.3124, 1.75, 1e3])
    want = [-29.51, -20.442, 0.0, 0.0, 0.0, 20.962, 38.87]
    np.testing.assert_allclose(sdp_rate(v, -29.51, 1.356, -1.3298, 38.87, 1.771, 1.3124), want,
                               atol=5e-4)
    np.testing.assert_array_equal(j2.rate(v), sdp_rate(v, -29.51, 1.356, -1.3298, 38.87, 1.771,
                                                       1.3124))
    # With alpha_1 and alpha_4 (deg per sample) the same function gives the increment q(v).
    np.testing.assert_allclose(sdp_rate(v, *J2_ALPHA), 0.01 * j2.rate(v), rtol=1e-12)
    assert float(sdp_rate(-2.2, *J2_ALPHA)) == pytest.approx(-0.20442, abs=5e-6)


def test_chord_commands_at_two_thirds_of_saturation(j2):
    v_min, v_max = chord_commands(j2.static_map)
    assert v_min == pytest.approx(-1.3298 - math.log(3.0) / 1.356, rel=1e-12)
    assert v_min == pytest.approx(-2.14, abs=0.01)
    assert v_max == pytest.approx(1.3124 + math.log(3.0) / 1.771, rel=1e-12)
    assert v_max == pytest.approx(1.93, abs=0.01)
    np.testing.assert_allclose(j2.rate(np.array([v_min, v_max])), [-29.51 * 2 / 3, 38.87 * 2 / 3],
                               rtol=1e-12)
    with pytest.raises(ConfigurationError, match='in \\(0, 1\\)'):
        chord_commands(j2.static_map, 1.0)


def test_shifted_map_moves_the_edges_only():
    sdp = EXAMPLE_MAPS[0]
    moved = shifted_map(sdp, (0.5, -0.25))
    assert isinstance(moved, SdpMap)
    assert moved.dead_zone == pytest.approx((-0.8298, 1.0624), abs=1e-12)
    assert (moved.saturation_velocity, moved.curvature) == ((-29.51, 38.87), (1.356, 1.771))
    assert shifted_map(EXAMPLE_MAPS[1], (1.0, 1.0)) == SdpDzMap((0.0, 3.0), (10.0, 20.0))
    assert shifted_map(EXAMPLE_MAPS[2], (0.0, 0.0)) is EXAMPLE_MAPS[2]
    for static_map in EXAMPLE_MAPS[2:5]:
        with pytest.raises(ConfigurationError, match='needs an sdp or sdp_dz model'):
            shifted_map(static_map, (0.1, 0.1))


@pytest.mark.parametrize(('static_map', 'rest'), [
    (SdpMap((-1.33, 1.31), (-29.5, 38.9), (1.36, 1.77)), 0.0),
    (SdpMap((40.0, 58.0), (-12.0, 15.0), (0.08, 0.1)), 49.0),
    (SdpDzMap((-3.0, -1.0), (10.0, 20.0)), -2.0),
    (LinearMap(12.0), 0.0),
    (PwlMap((20.0, 45.0, 55.0, 80.0), (-30.0, 0.0, 0.0, 30.0)), 50.0),
])
def test_rest_command_is_a_property_of_the_model(static_map, rest):
    assert JointModel('j', static_map, 0.1).rest_command == rest


def test_names_of_modes_and_lists():
    assert IDZ_MODES == ('zero', 'smooth', 'hysteresis')
    assert [idz_mode(name) for name in IDZ_MODES] == list(IDZ_MODES)
    with pytest.raises(ConfigurationError, match="one of zero, smooth, hysteresis, got 'soft'"):
        idz_mode('soft')
    with pytest.raises(ConfigurationError, match="got 'soft'"):
        InverseDeadZone((-1.0, 1.0), (1.0, 1.0), mode='soft')  # type: ignore[arg-type]
    assert require_float_list([1, 2.5], 'knots') == (1.0, 2.5)
    with pytest.raises(ModelFileError, match="key 'knots': expected a list of numbers"):
        require_float_list(3.0, 'knots')
    with pytest.raises(ModelFileError, match="key 'knots\\[1\\]': expected a number"):
        require_float_list([1.0, 'x'], 'knots')


def test_stroke_geometry_round_trips_through_the_model_file(tmp_path):
    geometry = StrokeGeometry(knots=(-10.0, 20.0, 60.0), factors=(0.7, 1.2, 0.9),
                              asymmetry=(0.1, 0.0, -0.1), cushion=3.0, cushion_factor=0.4)
    model = JointModel('arm', PowerSatMap((-37.5, 37.5), (-40.0, 32.0), (0.03, 0.04), (3.0, 2.5)),
                       0.25, angle_limits=(-10.0, 60.0), effects=(geometry, ValveLag(0.1)))
    path = save_model(model, tmp_path / 'model.yaml')
    text = path.read_text()
    assert 'stroke_geometry:' in text and 'knots:' in text and 'exponent:' in text
    assert load_model(path) == model


@pytest.mark.parametrize(('params', 'message'), [
    ({'knots': [0.0, 1.0], 'factors': [1.0]}, 'of equal number'),
    ({'knots': [1.0, 0.0], 'factors': [1.0, 1.0]}, 'strictly increasing'),
    ({'knots': [0.0, 1.0], 'factors': [1.0, -1.0]}, 'must be > 0'),
    ({'knots': [0.0, 1.0], 'factors': [1.0, 1.0], 'asymmetry': [0.0, 1.5]}, 'inside'),
    ({'knots': [0.0, 1.0], 'factors': [1.0, 1.0], 'cushion_factor': 0.0}, 'cushion_factor'),
    ({'knots': 3.0, 'factors': [1.0, 1.0]}, 'list of numbers'),
])
def test_bad_stroke_geometry_is_refused(params, message):
    with pytest.raises(ModelFileError, match=message):
        effect_from_mapping('stroke_geometry', params)

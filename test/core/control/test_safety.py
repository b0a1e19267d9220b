"""Set-points inside the stops, controllers and IDZs that fit the model, the hold at a stop."""

from dataclasses import replace

from hydro_sdp.core.control.controller_spec import design_from_model
from hydro_sdp.core.control.safety import (
    check_controller_fits, check_idz_fits, clamp_setpoint, controller_within_model,
    setpoint_range, slope_bounds, StopHold, top_speeds)
from hydro_sdp.core.errors import ConfigurationError
import pytest


def test_setpoints_are_kept_the_margin_inside_the_end_stops():
    stops = (-13.8, 63.6)
    assert setpoint_range(stops) == pytest.approx((-13.3, 63.1))
    assert clamp_setpoint(90.0, stops) == pytest.approx(63.1)
    assert clamp_setpoint(-20.0, stops, margin=2.0) == pytest.approx(-11.8)
    assert clamp_setpoint(63.2, stops) == pytest.approx(63.1)       # inside the stop, not margin
    assert clamp_setpoint(30.0, stops) == 30.0
    assert clamp_setpoint(63.6, stops, margin=0.0) == 63.6
    assert clamp_setpoint(1e6, None) == 1e6                         # no stops, no clamp
    assert clamp_setpoint(5.0, (0.0, 10.0), margin=5.0) == 5.0      # a single allowed angle


@pytest.mark.parametrize('margin', [-0.1, float('nan'), float('inf'), 6.0])
def test_a_bad_margin_is_refused(margin):
    with pytest.raises(ConfigurationError, match='setpoint_margin'):
        clamp_setpoint(1.0, (0.0, 10.0), margin=margin)


def test_a_controller_for_another_joint_or_beyond_the_valve_range_is_refused_with_the_fix(j2):
    spec = design_from_model(j2)
    check_controller_fits(spec, j2)
    with pytest.raises(ConfigurationError, match="controller is for joint 'j2', the model is "
                                                 "joint 'boom': design a controller from this "
                                                 r'model \(hydro-sdp design'):
        check_controller_fits(spec, replace(j2, joint='boom'))
    percent = replace(j2, input_limits=(0.0, 100.0),
                      static_map=replace(j2.static_map, dead_zone=(48.7, 51.3)))
    with pytest.raises(ConfigurationError,
                       match=r'commands the valve over \[-10.0, 10.0\], beyond the range '
                             r"\[0.0, 100.0\] of the model of joint 'j2': design the controller "
                             r'from this model .*identify --input-limits LOW HIGH'):
        check_controller_fits(spec, percent)
    # A controller for part of the valve's range runs a model of the whole of it.
    check_controller_fits(spec, replace(j2, input_limits=(-100.0, 100.0)))


def test_a_range_known_on_one_side_is_the_range(j2):
    # A model identified without --input-limits before they were recorded, or a controller
    # designed from one: the side that knows the valve's range gives it.
    unknown = replace(j2, input_limits=None)
    spec = design_from_model(unknown)
    assert spec.v_limits is None
    ran = controller_within_model(spec, j2)
    assert ran.v_limits == (-10.0, 10.0)
    assert ran.gains == spec.gains
    known = design_from_model(j2)
    assert controller_within_model(known, unknown).v_limits == (-10.0, 10.0)
    assert controller_within_model(spec, unknown).v_limits is None


def test_idz_edges_must_lie_inside_the_valve_range_and_slopes_within_the_models(j2):
    spec = design_from_model(j2)
    check_idz_fits(spec.idz, j2, 0.05, spec.v_limits)
    # J2 up: the chord to 10 V is 0.2237 deg per sample per V, the steepest 3.313.
    bounds = slope_bounds(j2, 0.05, None)
    assert bounds[1] == pytest.approx((0.2237, 3.313), rel=1e-3)
    idz = spec.idz
    with pytest.raises(ConfigurationError, match=r'IDZ edges \[-100.0, 100.0\] must lie inside '
                                                 r'the valve range \[-10.0, 10.0\]'):
        check_idz_fits(replace(idz, dead_zone=(-100.0, 100.0)), j2, 0.05, None)
    with pytest.raises(ConfigurationError, match='inside the valve range'):
        check_idz_fits(replace(idz, dead_zone=(-1.0, 10.0)), j2, 0.05, None)   # no room above
    with pytest.raises(ConfigurationError, match=r'IDZ negative slope 1e-300 lies outside '
                                                 r'\[0\.08509, 3\.886\]'):
        check_idz_fits(replace(idz, slopes=(1e-300, 1e-300)), j2, 0.05, None)
    with pytest.raises(ConfigurationError, match='IDZ positive slope 7 lies outside'):
        check_idz_fits(replace(idz, slopes=(1.2, 7.0)), j2, 0.05, None)
    check_idz_fits(replace(idz, slopes=(0.1, 6.0), dead_zone=(-1.0, 1.0)), j2, 0.05, None)
    # A table IDZ scaled to a slope the joint cannot have is refused the same way.
    table = design_from_model(j2, form='table').idz
    with pytest.raises(ConfigurationError, match='positive slope'):
        check_idz_fits(table.with_slopes((table.slopes[0], 1e-6)), j2, 0.05, None)


def test_without_a_valve_range_only_the_edges_order_counts(j2):
    open_valve = replace(j2, input_limits=None)
    assert top_speeds(open_valve) is None
    assert slope_bounds(open_valve, 0.05, None) == [None, None]
    idz = design_from_model(open_valve).idz
    check_idz_fits(replace(idz, slopes=(1e-3, 1e3)), open_valve, 0.05, None)
    assert top_speeds(j2) == pytest.approx((-29.51, 38.87), rel=1e-3)


def test_the_stop_hold_rests_near_a_stop_side_setpoint_only():
    allowed = (-13.3, 63.1)
    hold = StopHold(0.5)
    assert not hold.decide(30.0, 29.9, allowed)          # mid-range set-point: never
    assert not hold.decide(63.1, 62.5, allowed)          # stop-side, 0.6 deg short: control
    assert hold.decide(63.1, 62.7, allowed)              # within the band: hold
    assert hold.decide(63.1, 63.6, allowed)              # past it, at the stop: hold
    assert hold.decide(63.1, 62.2, allowed)              # falls back less than twice the band
    assert not hold.decide(63.1, 62.0, allowed)          # more: control again
    assert hold.decide(-13.0, -12.6, allowed)            # the lower stop, 0.3 deg from its end
    assert not hold.decide(-12.7, -12.6, allowed)        # 0.6 deg from it: not stop-side
    assert not StopHold(0.0).decide(63.1, 63.6, allowed)     # band 0: never
    assert not StopHold(0.5).decide(63.1, 63.6, None)        # no stops: never
    with pytest.raises(ConfigurationError, match='stop_band'):
        StopHold(-1.0)

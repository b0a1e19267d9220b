"""Set-points kept inside the end stops; controllers that do not fit the model are refused."""

from dataclasses import replace

from hydro_sdp.core.control.controller_spec import design_from_model
from hydro_sdp.core.control.safety import (
    check_controller_fits, clamp_setpoint, controller_within_model, setpoint_range)
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

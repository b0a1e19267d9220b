"""Set-points kept inside the end stops; controllers that do not fit the model are refused."""

from dataclasses import replace

from hydro_sdp.core.control.controller_spec import design_from_model
from hydro_sdp.core.control.safety import check_controller_fits, clamp_setpoint, setpoint_range
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


def test_a_controller_for_another_joint_or_valve_range_is_refused(j2):
    spec = design_from_model(j2)
    check_controller_fits(spec, j2)
    with pytest.raises(ConfigurationError, match="controller is for joint 'j2', the model is "
                                                 "joint 'boom'"):
        check_controller_fits(spec, replace(j2, joint='boom'))
    percent = replace(j2, input_limits=(-100.0, 100.0))
    with pytest.raises(ConfigurationError, match=r'valve range \[-10.0, 10.0\], the model of '
                                                 r"joint 'j2' has \[-100.0, 100.0\]"):
        check_controller_fits(spec, percent)
    with pytest.raises(ConfigurationError, match=r'has None'):
        check_controller_fits(spec, replace(j2, input_limits=None))

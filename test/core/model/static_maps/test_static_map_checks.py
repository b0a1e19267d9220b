"""The shared checks of the static maps' parameter pairs: which pairs pass, the exact errors."""

from hydro_sdp.core.errors import ModelFileError
from hydro_sdp.core.model.static_maps import PowerSatMap, SdpMap
from hydro_sdp.core.model.static_maps.protocol import (
    check_positive_pair, check_saturation_velocity)
import pytest


def test_saturation_speeds_must_be_negative_then_positive():
    check_saturation_velocity((-30.0, 25.0))
    for pair in ((30.0, 25.0), (-30.0, -25.0), (0.0, 25.0), (-30.0, 0.0)):
        with pytest.raises(ModelFileError) as raised:
            check_saturation_velocity(pair)
        assert str(raised.value) == ("key 'saturation_velocity': expected [negative, positive] "
                                     f'deg/s, got [{pair[0]}, {pair[1]}]')


def test_positive_pairs_name_their_key():
    check_positive_pair('curvature', (0.5, 1e-9))
    with pytest.raises(ModelFileError) as raised:
        check_positive_pair('exponent', (1.0, 0.0))
    assert str(raised.value) == "key 'exponent': both values must be > 0, got [1.0, 0.0]"


def test_the_maps_refuse_through_the_shared_checks():
    with pytest.raises(ModelFileError, match=r"^key 'curvature': both values must be > 0"):
        SdpMap((-1.0, 1.0), (-30.0, 25.0), (0.5, -0.5))
    with pytest.raises(ModelFileError, match=r"^key 'exponent': both values must be > 0"):
        PowerSatMap((-1.0, 1.0), (-30.0, 25.0), (0.5, 0.5), (1.0, 0.0))
    with pytest.raises(ModelFileError, match=r"^key 'saturation_velocity'"):
        PowerSatMap((-1.0, 1.0), (30.0, 25.0), (0.5, 0.5), (1.0, 1.0))

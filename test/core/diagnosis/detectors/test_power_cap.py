"""The pump's power cap of load_dependence and the choice of a form per direction."""

import math

from hydro_sdp.core.diagnosis.detectors.load_forms import joined, one_side
from hydro_sdp.core.diagnosis.detectors.power_cap import fit_power_cap
from hydro_sdp.core.errors import ModelFileError
from hydro_sdp.core.model.effects import LoadDependence
from hydro_sdp.core.model.exogenous_signals import Exogenous, exogenous_factor
from hydro_sdp.core.model.joint_model import JointModel
from hydro_sdp.core.model.static_maps import SdpDzMap
import numpy as np
import pytest


def model_with(effect: LoadDependence) -> JointModel:
    return JointModel('boom', SdpDzMap(dead_zone=(-0.5, 0.5), slope=(10.0, 10.0)), delay=0.05,
                      effects=(effect,))


def test_the_cap_holds_fast_commands_and_leaves_slow_ones() -> None:
    # 1000 deg/s x bar over (80 + 20) bar: at most 10 deg/s lifting; lowering uncapped.
    effect = LoadDependence(limit_positive=1000.0, limit_offset_positive=20.0)
    speed = np.array([5.0, 20.0, 40.0, -40.0, 20.0])
    load = Exogenous(load=np.array([80.0, 80.0, 80.0, 80.0, -30.0]))
    factor = exogenous_factor(model_with(effect), speed, load)
    assert factor is not None
    # Below the pressure offset the pump's pressure is no load's: no cap.
    np.testing.assert_allclose(factor, [1.0, 0.5, 0.25, 1.0, 1.0])
    data = model_with(effect).to_mapping()
    assert data['effects']['load_dependence']['limit_offset_positive'] == 20.0
    assert JointModel.from_mapping(data) == model_with(effect)
    with pytest.raises(ModelFileError, match='limit_'):
        LoadDependence(limit_negative=-1.0)
    with pytest.raises(ModelFileError, match='limit_'):
        LoadDependence(limit_offset_positive=math.nan)


def test_fit_power_cap_recovers_the_power_and_the_margin() -> None:
    rng = np.random.default_rng(7)
    dt, power, margin = 0.01, 2500.0, 20.0          # deg/s x bar, bar
    load = rng.uniform(10.0, 120.0, 5000)           # piston-side pressure, bar
    demanded = rng.uniform(5.0, 40.0, load.size)    # speed the valve asks, deg/s
    # Q p <= P with the pump at the load pressure plus its margin (written here, not imported).
    speed = np.minimum(demanded, power / (load + margin))
    measured = speed * dt + rng.normal(0.0, 0.003, load.size)
    c, offset = fit_power_cap(measured, demanded * dt, load)
    assert c / dt == pytest.approx(power, rel=0.05)
    assert offset == pytest.approx(margin, abs=3.0)
    # Without a cap nothing lowers the residual enough: no cap.
    assert fit_power_cap(demanded * dt + rng.normal(0.0, 0.003, load.size), demanded * dt,
                         load) == (0.0, 0.0)
    assert fit_power_cap(measured, demanded * dt, np.full(load.size, 3.0)) == (0.0, 0.0)


def test_each_direction_keeps_its_own_form() -> None:
    knots = (0.0, 50.0, 100.0)
    factor = LoadDependence(knots=knots, factors_positive=(1.0, 0.8, 0.6),
                            factors_negative=(0.9, 1.0, 1.2))
    cap = LoadDependence(limit_positive=900.0, limit_offset_positive=15.0,
                         overrun_negative=0.02, onset_negative=40.0)
    both = joined(cap, factor)
    assert both is not None
    assert (both.limit_positive, both.limit_offset_positive) == (900.0, 15.0)
    assert both.factors_negative == (0.9, 1.0, 1.2) and both.factors_positive == (1.0,) * 3
    assert both.overrun_negative == 0.0
    upside = one_side(factor, True)
    assert upside.factors_negative == (1.0,) * 3 and upside.factors_positive == (1.0, 0.8, 0.6)
    down = joined(None, cap)
    assert down is not None and down.limit_positive == 0.0 and down.overrun_negative == 0.02
    assert joined(None, None) is None

"""What stands in the way of a failed closed-loop check, on loops whose culprit is known."""

from dataclasses import replace

from hydro_sdp.core.control.controller_spec import design_from_model
from hydro_sdp.core.control.design_plant import completed_poles, plant_for_model
from hydro_sdp.core.control.idz_design import faded
from hydro_sdp.core.control.idz_table import TableInverseDeadZone
from hydro_sdp.core.control.loop_check import check_loop, CheckSettings
from hydro_sdp.core.control.loop_obstacles import (
    exact_map, obstacles, standing_in_the_way)
from hydro_sdp.core.model.effects import ValveLag
from hydro_sdp.core.model.static_maps import PwlMap, SdpDzMap
import numpy as np
import pytest

STROKE = (-13.8, 63.6)


def diagnosed(model, spec, settings, redesign):
    check = check_loop(model, spec, STROKE, settings=settings)
    assert not check.passed
    found = obstacles(model, spec, STROKE, settings, redesign)
    return {o.element: o for o in found}, standing_in_the_way(found, len(check.failures))


def test_an_over_compensating_idz_is_the_maps_fault(j2):
    # IDZ edges 0.1 V outside the true ones: the loop hunts (docs/methods.md 4.6).
    spec = design_from_model(j2)
    wide = replace(spec.idz, dead_zone=(spec.idz.dead_zone[0] - 0.1,
                                        spec.idz.dead_zone[1] + 0.1))
    found, named = diagnosed(j2, replace(spec, idz=wide), CheckSettings(noise_std=0.01),
                             lambda model, poles: replace(design_from_model(model, poles=poles),
                                                          idz=wide))
    assert named == ('map',)
    assert not found['noise'].passed and not found['delay'].passed


def test_a_band_narrower_than_the_noise_is_the_noises_fault(j2):
    spec = design_from_model(j2, beta=0.002)
    found, named = diagnosed(j2, spec, CheckSettings(noise_std=0.05),
                             lambda model, poles: design_from_model(model, poles=poles,
                                                                    beta=0.002))
    assert named == ('noise',)
    assert not found['map'].passed


def test_a_lag_the_design_ignores_is_the_lags_fault(j2):
    lagged = j2.with_effect(ValveLag(0.35))
    spec = design_from_model(j2)                       # the integrator alone
    found, named = diagnosed(lagged, spec, CheckSettings(),
                             lambda model, poles: design_from_model(model, poles=poles))
    assert 'lag' in named and not found['map'].passed
    # The redesign for the lag-free model kept the dominant poles of the failed design.
    assert found['lag'].passed


def _faded_design(model, poles):
    spec = design_from_model(model, poles=poles)
    return replace(spec, idz=faded(spec.idz))


def test_poles_too_fast_for_the_delay_are_the_delays_fault(j2):
    # With the delay of one sample these poles pulse at hold through the zero band alone
    # (0.62 pulses/s without noise), so the IDZ fades in, as calibrate takes it then.
    slow = replace(j2, delay=0.5)
    poles = completed_poles(plant_for_model(slow, 0.05), [0.85 + 0.08j, 0.85 - 0.08j])
    found, named = diagnosed(slow, _faded_design(slow, poles), CheckSettings(), _faded_design)
    assert 'delay' in named and found['delay'].passed
    assert 'lag' not in found and 'noise' not in found      # nothing to idealise there


def test_the_exact_map_of_each_idz_form(j2):
    chord = design_from_model(j2)
    exact = exact_map(chord)
    assert isinstance(exact, SdpDzMap)
    assert exact.slope == pytest.approx(np.asarray(chord.idz.slopes) / 0.05)
    table = design_from_model(j2, form='table')
    assert isinstance(table.idz, TableInverseDeadZone)
    exact = exact_map(table)
    assert isinstance(exact, PwlMap)
    v = np.linspace(-10.0, 10.0, 101)
    np.testing.assert_allclose(exact.rate(v) * 0.05, [table.idz.increment(x) for x in v])

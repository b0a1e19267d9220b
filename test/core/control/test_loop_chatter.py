"""
The valve's pulses at hold: counted as methods.md 5.7 defines them, failed by the check, faded out.

The pulsing case is J2 with a 0.12 s valve lag, a table IDZ and 0.03 deg of angle noise
(the lagged J2 of methods.md 5.5). Its controller files also run an independent J2 (eq. (5)
written here as a table of speeds, a spool lag before it: :mod:`support.table_valve_joint`)
in the loop of :mod:`support.independent_loop`, which reads the file and counts the pulses
with its own code.
"""

from dataclasses import replace
import math

from hydro_sdp.core.control.controller_spec import design_from_model
from hydro_sdp.core.control.idz import InverseDeadZone
from hydro_sdp.core.control.idz_design import faded
from hydro_sdp.core.control.idz_mapping import idz_from_mapping, idz_to_mapping
from hydro_sdp.core.control.loop_chatter import (
    MAX_PULSE_RATE, pulse_starts, valve_states)
from hydro_sdp.core.control.loop_check import check_loop, CheckSettings
from hydro_sdp.core.errors import ConfigurationError
from hydro_sdp.core.model.effects import ValveLag
from hydro_sdp.io.controller_files import save_controller
import numpy as np
import pytest
from support.independent_loop import FileController, judge, run_loop
from support.table_valve_joint import TableJoint, TableJointSimulator

pytestmark = pytest.mark.slow(6)

EDGES = (-1.3298, 1.3124)


def _pulses(v, edges=EDGES, rest=0.0):
    return pulse_starts(valve_states(np.asarray(v, dtype=float), edges, rest)).size


def test_pulses_are_openings_across_the_dead_zone():
    # Rest -> beyond the upper edge -> rest, twice: two pulses.
    assert _pulses([0, 0, 1.5, 1.6, 0, 0, 1.4, 0]) == 2
    # Beyond one edge straight to beyond the other: one; and back: two.
    assert _pulses([1.5, -1.5]) == 1 and _pulses([1.5, -1.5, 1.5]) == 2
    # A valve that slides out through the outer half of the dead-zone counts as one that jumps.
    assert _pulses([0, 0.8, 1.2, 1.4, 1.2, 0.3, 0]) == 1
    # Hovering at the edge (open, then just inside, open again) is no new opening ...
    assert _pulses([0, 1.4, 1.2, 1.35, 1.1, 1.4]) == 1
    # ... nor is jitter around rest, nor a valve open when the hold starts.
    assert _pulses([0.1, -0.2, 0.3, -0.1]) == 0 and _pulses([2.0, 2.1, 1.9]) == 0
    # Rest off the middle (percent resting at 50): closed within half-way to each edge.
    assert _pulses([50, 70, 50, 30, 50], edges=(32.0, 68.0), rest=50.0) == 2


def test_the_fade_in_band_leaves_rest_continuously():
    chord = InverseDeadZone(EDGES, (1.2, 2.1), beta=0.05)
    fading = replace(chord, fade=0.1)
    # Inside the band both rest; just beyond it the band jumps to the edge, the fade does not.
    assert chord.command(0.05)[0] == fading.command(0.05)[0] == 0.0
    assert chord.command(0.0501)[0] == pytest.approx(EDGES[1] + 0.0501 / 2.1)
    assert fading.command(0.0501)[0] == pytest.approx(1e-3 * (EDGES[1] + 0.0501 / 2.1), rel=1e-3)
    # tanh((|u| - beta) / fade) of the chord's command, on both sides.
    for u in (0.08, 0.15, 0.4, -0.12):
        v = chord.command(u)[0]
        assert fading.command(u)[0] == pytest.approx(math.tanh((abs(u) - 0.05) / 0.1) * v)
    # Far beyond the band the two agree; with fade 0 everywhere.
    assert fading.command(1.0)[0] == pytest.approx(chord.command(1.0)[0], rel=1e-6)
    assert replace(fading, fade=0.0) == chord
    # The file keeps the band; only the zero mode fades in.
    assert idz_from_mapping(idz_to_mapping(fading)) == fading
    assert 'fade' not in idz_to_mapping(chord)
    with pytest.raises(ConfigurationError, match='mode zero, not hysteresis'):
        replace(chord, mode='hysteresis', fade=0.1)
    with pytest.raises(ConfigurationError, match='>= 0'):
        replace(chord, fade=-0.1)


def _true_j2():
    """J2 written from eq. (5) as a table of speeds, a 0.12 s spool lag, 0.03 deg of noise."""
    def speed(v):
        if v < EDGES[0]:
            return -29.51 * (1.0 - math.exp(1.356 * (v - EDGES[0])))
        if v > EDGES[1]:
            return 38.87 * (1.0 - math.exp(-1.771 * (v - EDGES[1])))
        return 0.0
    volts = np.r_[np.linspace(-10.0, EDGES[0], 40), np.linspace(EDGES[1], 10.0, 40)]
    return TableJoint(duty=tuple(10.0 * volts), speed=tuple(speed(v) for v in volts),
                      dead_time=0.15, lag=0.12, stroke=(-13.8, 63.6), units_per_percent=0.1,
                      noise=0.03)


def test_a_pulsing_idz_fails_the_check_and_its_fade_holds_still(j2, tmp_path):
    lagged = j2.with_effect(ValveLag(0.12))
    band = design_from_model(lagged, form='table', noise_std=0.03)
    fade = replace(band, idz=faded(band.idz))
    settings = CheckSettings(noise_std=0.03)
    before = check_loop(lagged, band, j2.angle_limits, settings=settings)
    after = check_loop(lagged, fade, j2.angle_limits, settings=settings)
    # methods.md 5.7: 0.87 pulses/s at hold; faded, none, and the steps settle in 3.0-3.2 s
    # instead of 3.5-3.9 s (the valve still travels as much, sliding inside the dead-zone).
    assert not before.passed and before.chatter.pulse_rate > 1.5 * MAX_PULSE_RATE
    assert any(f.startswith('pulses at hold: ') and 'reversals/s' in f for f in before.failures)
    assert after.passed and after.chatter.pulse_rate < 0.2 * MAX_PULSE_RATE
    assert after.settling_range[1] < before.settling_range[1]
    # The files on the independent J2: the band pulses at hold, the fade does not.
    truth = _true_j2()
    rates, travel = [], []
    for name, spec in (('band', band), ('fade', fade)):
        controller = FileController.read(save_controller(spec, tmp_path / f'{name}.yaml'))
        run = run_loop(controller, TableJointSimulator(truth, 0.01, 10.0, seed=3), 0.01,
                       (10.0, 30.0, 50.0, 30.0, 10.0), 10.0)
        results = judge(run, rest=controller.rest, edges=EDGES)
        assert all(r.settling < 7.0 for r in results)
        held = sum(r.held for r in results)
        rates.append(sum(r.pulses for r in results) / held)
        travel.append(sum(r.travel for r in results) / held)
    # 2.6 pulses/s and 7.0 V/s of travel with the band alone, none and 0.9 V/s faded.
    assert rates[0] > 2.0 * MAX_PULSE_RATE and rates[1] < 0.2 * MAX_PULSE_RATE, rates
    assert travel[1] < 0.3 * travel[0], travel

"""
The check over the machines the data do not rule out (docs/methods.md section 5.8).

The models are one change each from the identified one; the worst case they report is
held against an independent loop (``support.independent_loop``) on a joint written without
the package (``support.plain_joint``) and on that joint changed as the models are.
"""

from dataclasses import replace

from hydro_sdp.core.control.controller_spec import design_from_model
from hydro_sdp.core.control.loop_check import CheckSettings
from hydro_sdp.core.control.plausible_models import check_over, plausible_models
from hydro_sdp.core.identification.identify import identify
from hydro_sdp.core.model.effects import ValveLag
from hydro_sdp.core.model.joint_model import JointModel
from hydro_sdp.core.model.static_maps import PolyMap, PwlMap
from hydro_sdp.core.model.undetermined import Undetermined
from hydro_sdp.io.controller_files import save_controller
import numpy as np
import pytest
from support.independent_loop import FileController, judge, run_loop
from support.plain_joint import PlainJoint, PlainPlant


def test_each_model_is_one_change_from_the_identified_one(j2):
    model = replace(j2, effects=(ValveLag(0.1),), undetermined=(
        Undetermined('dead_zone[0]', (-2.0, -1.0), 'no command between -1 and -2 was held'),))
    found = {p.name: p.model for p in plausible_models(
        model, dt=0.01, standard_errors={
            'dead_zone[0]': 0.05, 'dead_zone[1]': 0.05, 'saturation_velocity[1]': 1.5,
            'delay': 0.01, 'beta': 0.1})}
    assert sorted(found) == sorted([
        'dead_zone[1] -2 SE', 'dead_zone[1] +2 SE', 'saturation_velocity[1] -2 SE',
        'saturation_velocity[1] +2 SE', 'dead_zone[0] at the low end of its bound, -2',
        'dead_zone[0] at the high end of its bound, -1', 'delay -1 sample', 'delay +1 sample',
        'valve_lag x0.5', 'valve_lag x1.5'])
    assert found['dead_zone[1] -2 SE'].dead_zone == pytest.approx((j2.dead_zone[0],
                                                                   j2.dead_zone[1] - 0.1))
    assert found['saturation_velocity[1] +2 SE'].static_map.to_mapping()[
        'saturation_velocity'][1] == pytest.approx(38.87 + 3.0)
    assert found['dead_zone[0] at the low end of its bound, -2'].dead_zone[0] == -2.0
    assert [found[f'delay {s}1 sample'].delay for s in '-+'] == pytest.approx([0.14, 0.16])
    assert [found[f'valve_lag x{f}'].effects[0].time_constant for f in ('0.5', '1.5')] == \
        pytest.approx([0.05, 0.15])
    # Everything else is the identified model's.
    for name, other in found.items():
        assert other.joint == model.joint and other.angle_limits == model.angle_limits, name


#: An independent joint with a valve lag; the loop holds it at set-points across its stroke.
TRUE = PlainJoint(delay=12, dead_zone=(-0.9, 0.8), slope=(14.0, 18.0), saturation=(45.0, 55.0),
                  lag=0.06, noise=0.02)
LEVELS = (10.0, 35.0, 15.0, -10.0)


def _steps(joint):
    records = []
    for seed, level in enumerate((-4.0, -2.5, -1.6, -1.2, -0.8, 0.7, 1.1, 1.5, 2.4, 4.0)):
        v = np.where(np.arange(500) < 100, 0.0, level)
        records.append(joint.run(v, y0=5.0 if level > 0 else 40.0, seed=seed))
    return records


def test_the_worst_case_bounds_the_true_joint_changed_as_the_models_are(tmp_path):
    found = identify(_steps(TRUE))
    spec = design_from_model(found.model)
    settings = CheckSettings(noise_std=0.02)
    checked = check_over(plausible_models(found.model,
                                          standard_errors=found.fit.standard_errors,
                                          dt=0.01), spec, (-30.0, 60.0), settings)
    worst = checked.worst()
    assert len(checked.checks) >= 10, checked.to_mapping()
    controller = save_controller(spec, tmp_path / 'c.yaml')
    # The true joint, and the same joint with its delay a sample longer and its edges moved
    # by two of the identification's standard errors: each is one of the models checked.
    se = found.fit.standard_errors
    variants = [TRUE, replace(TRUE, delay=TRUE.delay + 1),
                replace(TRUE, dead_zone=(TRUE.dead_zone[0] - 2 * se['dead_zone[0]'],
                                         TRUE.dead_zone[1] + 2 * se['dead_zone[1]']))]
    for truth in variants:
        run = run_loop(FileController.read(controller), PlainPlant(truth, 0.0, seed=3), 0.01,
                       (0.0,) + LEVELS, 12.0)
        steps = judge(run, edges=truth.dead_zone)
        # Measured: settling 2.87-3.34 s against the worst 3.43 s; pulses 0.19-0.46/s
        # against 0.50/s; overshoot 0.3-1.2 % against 0.5 % (1 % of a 20 deg step is 0.2 deg).
        assert max(s.settling for s in steps) <= worst['settling_time'][0] + 0.5, truth
        assert max(s.overshoot for s in steps) <= worst['overshoot'][0] + 2.0, truth
        rate = sum(s.pulses for s in steps) / sum(s.held for s in steps)
        assert rate <= worst['pulse_rate'][0] + 0.25, truth


@pytest.mark.parametrize('static_map, limits, bound, rest', [
    # A table with a 30 % dead-zone each side (duty resting at 0).
    (PwlMap((-100.0, -30.0, 30.0, 100.0), (-40.0, 0.0, 0.0, 50.0)), (-100.0, 100.0),
     (0.0, 40.0), 0.0),
    # A polynomial with no dead-zone of its own, duty resting at 50.
    (PolyMap((0.8, 0.004), (1.0, 0.005), (0.0, 100.0), rest=50.0), (0.0, 100.0),
     (50.0, 70.0), 50.0),
    # Without input limits: the table's own knots bound the stretch.
    (PwlMap((-90.0, -30.0, 30.0, 90.0), (-40.0, 0.0, 0.0, 50.0)), None, (0.0, 40.0), 0.0),
])
def test_an_undetermined_edge_moves_on_maps_without_an_edge_key(
        static_map, limits, bound, rest):
    model = JointModel(joint='boom', static_map=static_map, delay=0.1, input_limits=limits,
                       undetermined=(Undetermined('dead_zone[1]', bound, 'hold lower'),))
    found = {p.name: p.model for p in plausible_models(model, standard_errors={},
                                                       dt=0.01)}
    assert model.rest_command == rest
    limits = limits or (static_map.knots[0], static_map.knots[-1])
    moved = [(name, m) for name, m in found.items() if name.startswith('dead_zone[1] at')]
    ends = {name.rsplit(', ', 1)[1]: m for name, m in moved}
    # An end that is where the map's edge already lies is not a change, and is not tried.
    edge = static_map.dead_zone[1] if static_map.dead_zone else rest
    assert sorted(ends) == sorted(f'{end:.4g}' for end in bound if end != edge)
    for end, changed in ends.items():
        value = float(end)
        assert changed.dead_zone[1] == pytest.approx(value, abs=1e-6)
        # Only the edge moves: the joint still above it, the valve's limit and the other
        # side give the speeds they gave.
        assert changed.rate(value + 0.5)[()] > 0.0
        assert changed.rate(limits[1])[()] == pytest.approx(model.rate(limits[1])[()])
        other = np.linspace(limits[0], rest, 9)
        np.testing.assert_allclose(changed.rate(other), model.rate(other), atol=1e-9 * 50)

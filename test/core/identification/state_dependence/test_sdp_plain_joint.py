"""The SDP analysis on a joint simulated apart from the package (test/support/plain_joint)."""

from hydro_sdp.core.errors import ConfigurationError, DataError
from hydro_sdp.core.identification.identify import identify
from hydro_sdp.core.identification.state_dependence import analyse, SdpAnalysis
from hydro_sdp.core.model.joint_model import JointModel
from hydro_sdp.core.model.records import Record
import numpy as np
import pytest
from support.plain_joint import PlainJoint, steps

#: A joint whose map has a dead-zone, a rise and a saturation well inside the command range,
#: and a valve lag of 50 ms.
JOINT = {'lag': 0.05, 'slope': (22.0, 25.0), 'saturation': (45.0, 50.0), 'stops': (-90.0, 90.0)}
STATES = ['command', 'angle', 'since_change']


def step_experiments(joint: PlainJoint, seed: int) -> list[Record]:
    """Step 1-8 units each way from rest, each step its own record from its own angle."""
    rng = np.random.default_rng(seed)
    records = []
    for i, size in enumerate(np.linspace(1.0, 8.0, 12)):
        for sign in (1.0, -1.0):
            records.append(joint.run(steps([sign * size], hold=1.5),
                                     y0=float(rng.uniform(-20.0, 20.0)),
                                     seed=100 * seed + 2 * i + (sign > 0),
                                     source=f'step {sign * size:+.2f}'))
    return records


@pytest.fixture(scope='module')
def model() -> JointModel:
    """Identify the joint from its steps, without a stroke factor (it has none)."""
    found = identify(step_experiments(PlainJoint(**JOINT), 9)).model
    return found.without_effect('stroke_geometry')


@pytest.fixture(scope='module')
def steps_analysis() -> SdpAnalysis:
    return analyse(step_experiments(PlainJoint(**JOINT), 1), states=STATES)


def test_step_experiments_show_an_integrator_whose_gain_depends_on_the_delayed_command(
        steps_analysis):
    result = steps_analysis
    assert result.target == 'arx'
    # a1 = -1 (paper's sign): the joint integrates; constant along the angle.
    assert result.a1 is not None and abs(result.a1.mean + 1.0) < 0.01
    assert result.a1.se < 1e-3
    first = result.states[0]
    assert first.state == 'command' and first.significant
    assert {e.direction for e in result.states if e.state == 'command'} == {'positive',
                                                                            'negative'}
    # The dead time (120 ms) plus the lag (50 ms), at 10 ms.
    assert abs(result.delay - 17) <= 2
    # The gain's shape is the map's: b = speed dt / v, small at the dead-zone, largest past
    # it, falling as the speed saturates (read against the generator's own map).
    joint = PlainJoint(**JOINT)
    for entry in result.dependence('command'):
        truth = np.array([joint.speed(v) * joint.dt / v for v in entry.values])
        assert np.max(np.abs(entry.estimate - truth)) < 0.2 * np.max(truth)
        peak = int(np.argmax(entry.estimate))
        assert 0 < peak < entry.values.size - 1


def test_a_joint_with_an_angle_effect_shows_the_angle_first(model):
    joint = PlainJoint(**JOINT, angle_factor=lambda a, d: 1.0 + 0.25 * np.sin(np.radians(2.5 * a)))
    runs = [joint.run_levels(60.0, seed=seed) for seed in (3, 4)]
    result = analyse(runs, model=model, states=STATES)
    assert result.target == 'ratio' and result.a1 is None
    first = result.states[0]
    assert first.state == 'angle' and first.significant and first.share > 0.2
    # Both directions follow the same factor of the angle: 1 + 0.25 sin(2.5 a).
    for entry in result.dependence('angle', parameter='ratio'):
        inside = np.abs(entry.values) < 70.0
        factor = 1.0 + 0.25 * np.sin(np.radians(2.5 * entry.values[inside]))
        shape = np.corrcoef(entry.estimate[inside], factor)[0, 1]
        assert shape > 0.9


def test_a_measured_load_shows_the_load_first(model):
    # Lifting against the load slows the joint, lowering with it speeds it up.
    joint = PlainJoint(**JOINT, load_factor=lambda load, d: 1.0 - 0.004 * load if d > 0
                       else 1.0 + 0.002 * load)
    runs = [joint.run_levels(40.0, seed=seed, load=lambda t, level=level: level + 10.0 * np.sin(
        0.5 * t)) for seed, level in ((5, 20.0), (6, 120.0), (7, 70.0))]
    result = analyse(runs, model=model, states=['command', 'angle', 'load'])
    first = result.states[0]
    assert first.state == 'load' and first.significant
    up = result.dependence('load', 'positive', 'ratio')[0]
    down = result.dependence('load', 'negative', 'ratio')[0]
    # The ratio follows the factor per direction, relative to the model's own load (the
    # steps were run without any).
    slope_up = np.polyfit(up.values, up.estimate, 1)[0]
    slope_down = np.polyfit(down.values, down.estimate, 1)[0]
    assert slope_up == pytest.approx(-0.004, rel=0.25)
    assert slope_down == pytest.approx(0.002, rel=0.35)


def test_the_model_of_the_joint_misses_little(model):
    runs = [PlainJoint(**JOINT).run_levels(60.0, seed=seed) for seed in (11, 12)]
    result = analyse(runs, model=model, states=STATES)
    # No angle effect is found where there is none.
    for entry in result.dependence('angle', parameter='ratio'):
        assert entry.share < 0.02
    for entry in result.states:
        assert abs(float(np.median(entry.estimate)) - 1.0) < 0.1


def test_bad_input_is_refused_with_a_one_line_error():
    joint = PlainJoint(**JOINT)
    record = joint.run(steps([2.0, -2.0]), seed=1)
    with pytest.raises(ConfigurationError, match="unknown state 'speed'"):
        analyse([record], states=['speed'])
    with pytest.raises(ConfigurationError, match='named twice'):
        analyse([record], states=['angle', 'angle'])
    with pytest.raises(DataError, match='no state could be analysed.*load'):
        analyse([record], states=['load', 'others_speed'])
    still = Record(record.t, np.zeros(len(record)), record.y, 'plain')
    with pytest.raises(DataError, match='never drives'):
        analyse([still], states=['angle'], delay=5)
    with pytest.raises(DataError, match='no records'):
        analyse([])


def test_a_percent_duty_valve_resting_at_50_gives_the_same_answer(steps_analysis):
    # The same steps written as a 0..100 % duty resting at 50 (5 % per unit).
    duty = [Record(r.t, 50.0 + 5.0 * r.v, r.y, r.joint, r.source, r.origin)
            for r in step_experiments(PlainJoint(**JOINT), 1)]
    result = analyse(duty, states=STATES)
    assert result.rest == 50.0 and result.delay == steps_analysis.delay
    assert result.a1 is not None and abs(result.a1.mean + 1.0) < 0.01
    assert result.states[0].state == 'command'
    for entry in result.dependence('command'):
        volts = steps_analysis.dependence('command', entry.direction)[0]
        # The gain per percent is the gain per unit over 5, at the same commands.
        np.testing.assert_allclose(entry.values, 50.0 + 5.0 * volts.values)
        np.testing.assert_allclose(entry.estimate, volts.estimate / 5.0, rtol=0.05, atol=1e-4)

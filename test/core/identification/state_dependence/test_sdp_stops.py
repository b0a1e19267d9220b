"""Increments the joint cannot make are left out of the SDP analysis, and counted."""

from hydro_sdp.core.errors import DataError
from hydro_sdp.core.identification.state_dependence import analyse
from hydro_sdp.core.identification.state_dependence.states import HOLDS, rows_of
from hydro_sdp.core.model.joint_model import JointModel
import numpy as np
import pytest
from support.joint_generator import Joint, Machine, record, SpeedMap

DT = 0.01
#: A valve in percent resting at 50, stops at -35 and 40 deg.
JOINT = Joint(SpeedMap('exp', (38.0, 62.0), (30.0, 35.0), (0.08, 0.09)), delay=0.12,
              stops=(-35.0, 40.0), noise=0.02)


def test_a_stop_a_rest_at_it_and_a_stall_are_each_marked():
    # Up into the top stop and held 2 s there, rest at it, down to the middle, then down
    # again while a load stalls the joint (its speed factor 0) from 10.8 s to 12.8 s.
    v = np.r_[np.full(100, 50.0), np.full(450, 90.0), np.full(150, 50.0), np.full(200, 20.0),
              np.full(100, 50.0), np.full(600, 25.0), np.full(100, 50.0)]
    load = np.zeros(v.size)
    load[1080:1280] = 1.0
    stalling = Joint(JOINT.speed_map, delay=JOINT.delay, stops=JOINT.stops, noise=JOINT.noise,
                     load_factor=lambda load, direction: 1.0 - load)
    run = record(Machine((stalling,)), v[:, None], angles0=[0.0], load=load, seed=4)
    rows = rows_of([run], 12, 50.0, holds=True)
    k = np.arange(12, v.size)
    code = dict(zip(k.tolist(), rows.hold.tolist()))
    # Driven into the stop (reached about 2.9 s after the 1 s start), held until the
    # command rests and the delay passes; then resting there until the command drives down.
    assert all(code[i] == 1 for i in range(420, 560))
    assert all(code[i] == 3 for i in range(580, 700))
    assert all(code[i] == 0 for i in range(715, 890))
    # Stalled mid-stroke: held after moving under a command that still drives it (from the
    # window that sees the stall, less the last window before the joint moves again).
    assert np.mean([code[i] == 2 for i in range(1100, 1280)]) > 0.8
    assert all(code[i] == 0 for i in range(1300, 1350))
    free, left = rows.free()
    assert set(left) == set(HOLDS.values())
    assert free.samples == rows.samples - sum(left.values())
    assert not np.any(free.hold)


def program(seed: int) -> np.ndarray:
    """Full strokes at random duties, each pushed 3-8 s against the stop it reaches."""
    rng = np.random.default_rng(seed)
    parts, y = [np.full(100, 50.0)], 0.0
    for _ in range(6):
        up = y < 0.0
        duty = float(rng.uniform(66.0, 100.0)) if up else float(rng.uniform(0.0, 34.0))
        travel = (40.0 - y) if up else (y + 35.0)
        hold = travel / abs(JOINT.speed_map.speed(duty)) + float(rng.uniform(3.0, 8.0))
        parts += [np.full(int(hold / DT), duty), np.full(int(rng.uniform(0.5, 1.0) / DT), 50.0)]
        y = 40.0 if up else -35.0
    return np.concatenate(parts)


def test_runs_that_sit_at_a_stop_with_the_command_on_name_the_command():
    # Held at the stop the increment is zero while the command drives: with those samples
    # the angle came first (shares 0.88 and 0.71) and the command explained nothing, and the
    # duty held longest against a stop passed for the rest.
    runs = [record(Machine((JOINT,)), program(seed)[:, None], angles0=[0.0], seed=seed)
            for seed in (1, 2)]
    result = analyse(runs, states=['command', 'angle', 'since_change'], replicates=99)
    assert result.rest == 50.0
    assert result.left_out[HOLDS[1]] > result.samples
    assert result.states[0].state == 'command'
    # Six strokes each way cannot rule out a gain of each stroke's own (the test flips
    # whole runs): the command is first, the others add nothing.
    for entry in result.states[2:]:
        assert entry.share < 0.01 and not entry.significant


def test_records_held_at_a_stop_throughout_are_refused_naming_what_was_left_out():
    # The joint's own model knows the stop it sits at, pushed or at rest, all along.
    model = JointModel.from_mapping({
        'format': 'hydro_sdp/model/v1', 'joint': 'joint', 'kind': 'sdp', 'delay': 0.12,
        'angle_limits': [-35.0, 40.0], 'input_limits': [0.0, 100.0], 'dead_zone': [38.0, 62.0],
        'saturation_velocity': [-30.0, 35.0], 'curvature': [0.08, 0.09], 'effects': {}})
    v = np.r_[np.full(50, 50.0), np.full(1200, 95.0)]
    run = record(Machine((JOINT,)), v[:, None], angles0=[40.0], seed=2)
    with pytest.raises(DataError, match=r'only \d+ increments where the joint can move \(left '
                                        r'out: \d+ held at an end stop'):
        analyse([run], model=model, states=['command'], replicates=0)

"""Planar boom-dipper kinematics, the kinematics file and straight tip lines."""

import math

from hydro_sdp.core.control.kinematics import distance_to_segment, line_trajectory, TwoLinkArm
from hydro_sdp.core.control.safety import setpoint_range
from hydro_sdp.core.errors import DataError, ModelFileError
from hydro_sdp.io.documents import shipped_config
from hydro_sdp.io.model_files import load_model
from hydro_sdp.io.trajectory_files import load_kinematics, load_trajectory
import numpy as np
import pytest

ARM = TwoLinkArm(('boom', 'dipper'), (1.8, 1.0), (0.0, 0.0))


def test_known_configurations():
    assert ARM.forward(0.0, 0.0) == pytest.approx((2.8, 0.0))          # straight arm
    assert ARM.forward(90.0, 0.0) == pytest.approx((0.0, 2.8))
    assert ARM.forward(0.0, -90.0) == pytest.approx((1.8, -1.0))       # right angle
    assert ARM.forward(90.0, -90.0) == pytest.approx((1.0, 1.8))
    shifted = TwoLinkArm(('boom', 'dipper'), (1.8, 1.0), (30.0, -30.0))
    assert shifted.forward(-30.0, 30.0) == pytest.approx((2.8, 0.0))
    assert ARM.inverse(1.8, -1.0, 'up') == pytest.approx((0.0, -90.0))
    assert ARM.inverse(1.8, -1.0, 'down') == pytest.approx(
        (-2.0 * math.degrees(math.atan2(1.0, 1.8)), 90.0))
    # At full reach acos amplifies the rounding of its argument (sqrt(1e-16) ~ 1e-8 rad).
    assert ARM.inverse(2.8, 0.0) == pytest.approx((0.0, 0.0), abs=1e-5)


@pytest.mark.parametrize('elbow, sign', [('up', -1.0), ('down', 1.0)])
def test_forward_and_inverse_round_trip(rng, elbow, sign):
    arm = TwoLinkArm(('boom', 'dipper'), (1.7, 1.1), (12.0, -25.0))
    for _ in range(200):
        boom = rng.uniform(-170.0, 170.0)
        relative = sign * rng.uniform(1.0, 179.0)             # the dipper against the boom
        dipper = relative - arm.offsets[1]
        x, z = arm.forward(boom, dipper)
        got = arm.inverse(x, z, elbow)
        assert arm.forward(*got) == pytest.approx((x, z), abs=1e-9)
        assert math.remainder(got[0] - boom, 360.0) == pytest.approx(0.0, abs=1e-7)
        assert math.remainder(got[1] - dipper, 360.0) == pytest.approx(0.0, abs=1e-7)


def test_out_of_reach_is_a_clear_error():
    with pytest.raises(DataError, match=r'out of reach: its distance 3 m .* \[0.8, 2.8\] m'):
        ARM.inverse(3.0, 0.0)
    with pytest.raises(DataError, match='out of reach'):
        ARM.inverse(0.3, 0.0)
    with pytest.raises(DataError, match='elbow must be one of up, down'):
        ARM.inverse(2.0, 0.0, 'sideways')


def test_jacobian_is_the_derivative():
    boom, dipper, h = 25.0, -80.0, 1e-6
    numeric = np.array([
        (np.array(ARM.forward(boom + h, dipper)) - ARM.forward(boom - h, dipper)) / (2 * h),
        (np.array(ARM.forward(boom, dipper + h)) - ARM.forward(boom, dipper - h)) / (2 * h)]).T
    np.testing.assert_allclose(ARM.jacobian(boom, dipper), numeric, rtol=1e-7, atol=1e-10)


def test_line_points_lie_on_the_line_at_constant_speed():
    start, end = (1.6, 0.3), (2.3, -0.4)
    line = line_trajectory(ARM, start, end, speed=0.1, point_period=0.05)
    length = math.hypot(0.7, 0.7)
    assert line.duration == pytest.approx(length / 0.1)
    assert line.joint_names == ('boom', 'dipper')
    x, z = ARM.forward_many(line.positions[:, 0], line.positions[:, 1])
    assert np.max(distance_to_segment(x, z, start, end)) < 1e-9
    along = np.hypot(x - start[0], z - start[1])
    np.testing.assert_allclose(along, 0.1 * line.times, atol=1e-9)
    assert (x[-1], z[-1]) == pytest.approx(end, abs=1e-9)
    # The joint velocities give the tip the line's velocity.
    tip = np.array([ARM.jacobian(*q) @ qd for q, qd in zip(line.positions, line.velocities)])
    np.testing.assert_allclose(tip, np.tile([0.1 / math.sqrt(2), -0.1 / math.sqrt(2)],
                                            (len(tip), 1)), atol=1e-12)
    by_duration = line_trajectory(ARM, start, end, duration=4.0, point_period=0.3)
    assert by_duration.times[-1] == 4.0 and by_duration.times[-2] == pytest.approx(3.9)


def test_line_errors():
    with pytest.raises(DataError, match='speed or the duration'):
        line_trajectory(ARM, (1.6, 0.3), (2.3, -0.4))
    with pytest.raises(DataError, match='must differ'):
        line_trajectory(ARM, (1.6, 0.3), (1.6, 0.3), speed=0.1)
    with pytest.raises(DataError, match='out of reach'):
        line_trajectory(ARM, (1.6, 0.3), (3.3, -0.4), speed=0.1)


def test_distance_to_segment():
    d = distance_to_segment(np.array([0.5, -1.0, 3.0]), np.array([1.0, 0.0, 4.0]),
                            (0.0, 0.0), (1.0, 0.0))
    np.testing.assert_allclose(d, [1.0, 1.0, math.hypot(2.0, 4.0)])


def test_shipped_line_stays_inside_both_end_stops():
    plan = load_trajectory(shipped_config('lucie_line.yaml'))
    arm = load_kinematics(shipped_config('lucie_kinematics.yaml'))
    assert plan.arm == arm and arm.joints == ('boom', 'dipper')
    assert 1.5 <= arm.lengths[0] <= 2.0 and 0.8 <= arm.lengths[1] <= 1.2
    for column, name in enumerate(plan.trajectory.joint_names):
        low, high = setpoint_range(load_model(shipped_config(f'lucie_{name}.yaml')).angle_limits)
        values = plan.trajectory.positions[:, column]
        assert low < values.min() and values.max() < high
        assert values.max() - values.min() > 25.0              # both joints really move


@pytest.mark.parametrize('mapping, message', [
    ([], 'must be a mapping'),
    ({'format': 'x', 'links': []}, "key 'format': expected 'hydro_sdp/kinematics/v1'"),
    ({'format': 'hydro_sdp/kinematics/v1'}, "missing required key 'links'"),
    ({'format': 'hydro_sdp/kinematics/v1', 'links': [], 'extra': 1}, "unknown key 'extra'"),
    ({'format': 'hydro_sdp/kinematics/v1', 'links': [{'joint': 'boom', 'length': 1.0}]},
     'a list of two links'),
    ({'format': 'hydro_sdp/kinematics/v1',
      'links': [{'joint': 'boom', 'length': 1.8}, {'joint': 'dipper'}]},
     r'missing required key links\[1\].length'),
    ({'format': 'hydro_sdp/kinematics/v1',
      'links': [{'joint': 'boom', 'length': 1.8}, {'joint': 'dipper', 'length': -1.0}]},
     r"key 'links\[1\].length': must be > 0 m"),
    ({'format': 'hydro_sdp/kinematics/v1',
      'links': [{'joint': 'boom', 'length': 1.8, 'offset': 'a'},
                {'joint': 'dipper', 'length': 1.0}]},
     r"key 'links\[0\].offset': expected a number"),
    ({'format': 'hydro_sdp/kinematics/v1',
      'links': [{'joint': 'boom', 'length': 1.8}, {'joint': 'boom', 'length': 1.0}]},
     'the same joint'),
    ({'format': 'hydro_sdp/kinematics/v1',
      'links': [{'joint': 'boom', 'length': 1.8, 'mass': 3},
                {'joint': 'dipper', 'length': 1.0}]},
     r'unknown key links\[0\].mass'),
])
def test_kinematics_file_errors_name_the_key(mapping, message):
    with pytest.raises(ModelFileError, match=message):
        TwoLinkArm.from_mapping(mapping)


def test_kinematics_file_error_names_the_file(tmp_path):
    path = tmp_path / 'arm.yaml'
    path.write_text('format: hydro_sdp/kinematics/v1\nlinks: 3\n')
    with pytest.raises(ModelFileError, match=r"arm.yaml: key 'links'"):
        load_kinematics(path)

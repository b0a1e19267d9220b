"""Where the data's zero lies changes nothing: the sums are formed about a reference."""

from dataclasses import replace

from hydro_sdp.core.identification.state_dependence import analyse
from hydro_sdp.core.identification.state_dependence.backfit import backfit, Term
from hydro_sdp.core.identification.state_dependence.nvr import estimate_nvr
from hydro_sdp.core.identification.state_dependence.random_walk import group_stats
from hydro_sdp.core.model.joint_model import JointModel
import numpy as np
import pytest
from support.joint_generator import Joint, Machine, record, SpeedMap

#: Sensor noise of a real angle of about 150 deg, deg.
NOISE = 0.0007
#: Offsets added, in noises: up to 1e8 (70 000 deg).
OFFSETS = (1e4, 1e6, 1e7, 1e8)
JOINT = Joint(SpeedMap('exp', (-0.8, 0.9), (20.0, 25.0), (0.5, 0.6)), delay=0.08,
              stops=(120.0, 180.0), noise=NOISE)
#: A model of the joint whose lowering side is 15 % slow and rises more slowly: the ratio
#: depends on the command, so that its NVR is one the data determine.
MODEL = JointModel.from_mapping({
    'format': 'hydro_sdp/model/v1', 'joint': 'joint', 'kind': 'sdp', 'delay': 0.08,
    'angle_limits': [120.0, 180.0], 'input_limits': [-10.0, 10.0], 'dead_zone': [-0.8, 0.9],
    'saturation_velocity': [-17.0, 25.0], 'curvature': [0.35, 0.6], 'effects': {}})

pytestmark = [pytest.mark.slow(8)]


def test_a_level_far_from_zero_keeps_its_nvr_and_its_curve():
    # A local level (the increment residual's model) whose mean is 1e8 noises from zero:
    # sums of z itself would cancel to nothing in the squared residual.
    rng = np.random.default_rng(3)
    n = 3000
    z = np.cumsum(rng.normal(0.0, 0.1 * NOISE, n)) + rng.normal(0.0, NOISE, n)
    ones, group = np.ones(n), np.arange(n)
    base = estimate_nvr(group_stats(z, ones, group, n), 'rw')
    state = np.sort(rng.uniform(0.0, 10.0, n))
    fit = backfit(z, [Term('c', ones, state)], replicates=0).terms[0]
    assert base.nvr > 0.0
    for offset in OFFSETS:
        moved = z + offset * NOISE
        assert estimate_nvr(group_stats(moved, ones, group, n), 'rw').nvr == pytest.approx(
            base.nvr, rel=1e-6)
        term = backfit(moved, [Term('c', ones, state)], replicates=0).terms[0]
        assert term.nvr == pytest.approx(fit.nvr, rel=1e-6)
        np.testing.assert_allclose(term.estimate - offset * NOISE, fit.estimate, rtol=0.0,
                                   atol=1e-6 * NOISE)
        assert term.share == pytest.approx(fit.share, rel=1e-6, abs=1e-9)


def levels(rng: np.random.Generator, n: int) -> np.ndarray:
    """Random levels held 0.5-2 s, the joint kept between 125 and 175 deg."""
    v, k, y = np.zeros(n), 0, 150.0
    while k < n:
        level = (1.0 if rng.random() < (175.0 - y) / 50.0 else -1.0) * rng.uniform(0.5, 6.0)
        held = int(rng.uniform(50, 200))
        v[k:k + held] = level
        y = min(max(y + JOINT.speed_map.speed(level) * held * 0.01, 120.0), 180.0)
        k += held
    return v


@pytest.fixture(scope='module')
def records():
    """Two 25 s records of a joint at 120..180 deg with 0.0007 deg of noise."""
    rng = np.random.default_rng(1)
    return [record(Machine((JOINT,)), levels(rng, 2500)[:, None], angles0=[150.0], seed=seed)
            for seed in (1, 2)]


def moved(records, offset, model=None):
    """Add ``offset`` deg to every angle (and to the model's stops)."""
    shifted = [replace(r, y=r.y + offset) for r in records]
    if model is not None:
        low, high = model.angle_limits
        model = replace(model, angle_limits=(low + offset, high + offset))
    return shifted, model


def same(analysis, base):
    """Assert two analyses agree: every NVR to 1e-6, every curve to 1e-6 of its scale."""
    assert analysis.samples == base.samples and analysis.left_out == base.left_out
    entries = {(e.parameter, e.state, e.direction): e for e in base.states + base.residual}
    assert len(entries) == len(analysis.states + analysis.residual)
    for entry in analysis.states + analysis.residual:
        other = entries[(entry.parameter, entry.state, entry.direction)]
        assert entry.nvr == pytest.approx(other.nvr, rel=1e-6, abs=0.0)
        scale = max(float(np.max(np.abs(other.estimate))), float(np.max(other.se)))
        np.testing.assert_allclose(entry.estimate, other.estimate, rtol=0.0, atol=1e-6 * scale)


@pytest.mark.parametrize('target', ['arx', 'ratio'])
def test_angles_of_150_deg_and_0_0007_deg_of_noise_give_the_same_answer_moved(records, target):
    # arx: y_k - ybar = -a1 (y_{k-1} - ybar) + b u, from the angles' mean; ratio and
    # residual: increments, the model's stops moved with the angles.
    model = MODEL if target == 'ratio' else None
    states = ['command', 'angle']
    base = analyse(records, model=model, states=states, replicates=0)
    assert any(e.nvr > 0.0 for e in base.states)
    for offset in (1e6, 1e8):
        shifted, shifted_model = moved(records, offset * NOISE, model)
        analysis = analyse(shifted, model=shifted_model, states=states, replicates=0)
        same(analysis, base)
        if target == 'arx':
            assert analysis.a1.mean == pytest.approx(base.a1.mean, rel=1e-9)

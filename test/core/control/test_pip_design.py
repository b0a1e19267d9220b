"""PIP design: the paper's gains, random plants against python-control, LQ, refusals."""

from hydro_sdp.core.control.pip_design import (
    closed_loop_poles, DiscretePlant, lq_design, LqWeights, nmss, PipGains, pole_assignment)
from hydro_sdp.core.errors import ConfigurationError
import numpy as np
import pytest

PAPER_POLES = [0.94 + 0.05j, 0.94 - 0.05j, 0.0, 0.0]
PRINTED_POLES = [0.9 + 0.05j, 0.9 - 0.05j, 0.0, 0.0]


def test_nmss_of_the_papers_plant():
    model = nmss(DiscretePlant.integrator(3))
    np.testing.assert_array_equal(model.F, [[1, 0, 1, 0], [0, 0, 0, 0], [0, 1, 0, 0],
                                            [-1, 0, -1, 1]])
    np.testing.assert_array_equal(model.g, [0, 1, 0, 0])
    np.testing.assert_array_equal(model.d, [0, 0, 0, 1])
    controllability = np.column_stack([np.linalg.matrix_power(model.F, i) @ model.g
                                       for i in range(4)])
    assert np.linalg.matrix_rank(controllability) == 4


@pytest.mark.parametrize(('poles', 'expected'), [
    (PAPER_POLES, (0.1261, 0.12, 0.1261, 0.0061)),
    (PRINTED_POLES, (0.2125, 0.2, 0.2125, 0.0125)),
])
def test_pole_assignment_gives_the_papers_gains(poles, expected):
    gains = pole_assignment(DiscretePlant.integrator(3), poles)
    f0, g1, g2, k_i = expected
    np.testing.assert_allclose([gains.f[0], gains.g[0], gains.g[1], gains.k_i],
                               [f0, g1, g2, k_i], atol=1e-4)
    # The closed forms of docs/methods.md section 4.3 hold exactly.
    p1, p2 = poles[:2]
    assert gains.g[0] == pytest.approx((2 - (p1 + p2)).real, abs=1e-12)
    assert gains.f[0] == pytest.approx(gains.g[1], abs=1e-12)
    assert gains.k_i == pytest.approx(gains.g[1] - gains.g[0], abs=1e-12)


def test_printed_gains_place_the_poles_at_0_94():
    poles = closed_loop_poles(DiscretePlant.integrator(3), PipGains((0.1261,), (0.12, 0.1261),
                                                                    0.0061))
    np.testing.assert_allclose(np.sort_complex(poles[:2]), [0.94 - 0.05j, 0.94 + 0.05j],
                               atol=1e-3)
    assert np.all(np.abs(poles[2:]) < 1e-6)


@pytest.mark.parametrize(('weights', 'expected'), [
    (LqWeights(1.6567e-3, 1.0, 4.1993e-5), (0.1261, 0.12, 0.1261, 0.0061)),
    (LqWeights(1.5385e-2, 1.0, 1.9231e-4), (0.2125, 0.2, 0.2125, 0.0125)),
])
def test_lq_reproduces_the_papers_designs(weights, expected):
    gains = lq_design(DiscretePlant.integrator(3), weights)
    np.testing.assert_allclose([gains.f[0], gains.g[0], gains.g[1], gains.k_i], expected,
                               atol=1e-4)


@pytest.mark.parametrize('delay', range(1, 7))
def test_default_lq_keeps_the_papers_dominant_poles_at_any_delay(delay):
    plant = DiscretePlant.integrator(delay)
    poles = closed_loop_poles(plant, lq_design(plant))
    np.testing.assert_allclose(np.sort_complex(poles[:2]), [0.94 - 0.05j, 0.94 + 0.05j],
                               atol=1e-6)
    assert np.all(np.abs(poles[2:]) < 2e-3)


def _random_plant(rng):
    n = int(rng.integers(1, 4))
    roots = []
    while len(roots) < n:
        if rng.random() < 0.3:
            roots.append(1.0)                       # integrating
        elif n - len(roots) >= 2 and rng.random() < 0.5:
            radius, angle = rng.uniform(0.2, 0.95), rng.uniform(0.1, 2.5)
            roots += [radius * np.exp(1j * angle), radius * np.exp(-1j * angle)]
        else:
            roots.append(rng.uniform(-0.9, 0.95))
    a = np.real(np.poly(roots))[1:]
    delay = int(rng.integers(1, 6))
    numerator = rng.uniform(0.2, 2.0, int(rng.integers(1, 4))) * rng.choice([-1, 1])
    return DiscretePlant(a=tuple(a), b=(0.0,) * (delay - 1) + tuple(numerator))


def _random_poles(rng, count):
    poles = []
    while len(poles) < count:
        kind = rng.random()
        if kind < 0.25:
            poles.append(0.0)                        # at the origin, often repeated
        elif kind < 0.5 and count - len(poles) >= 2:
            radius, angle = rng.uniform(0.3, 0.9), rng.uniform(0.05, 1.0)
            poles += [radius * np.exp(1j * angle), radius * np.exp(-1j * angle)]
        elif kind < 0.65 and poles and count - len(poles) >= 1:
            poles.append(poles[-1] if np.isreal(poles[-1]) else 0.5)  # repeated
        else:
            poles.append(rng.uniform(0.0, 0.9))
    return poles


def test_random_plants_against_python_control(rng):
    control = pytest.importorskip('control')
    checked = 0
    while checked < 60:
        plant = _random_plant(rng)
        poles = _random_poles(rng, plant.n + plant.m)
        try:
            gains = pole_assignment(plant, poles)
        except ConfigurationError as error:
            assert 'not controllable' in str(error)  # a random B may share a root with A
            continue
        model = nmss(plant)
        reference = np.asarray(control.acker(model.F, model.g.reshape(-1, 1), poles)).ravel()
        np.testing.assert_allclose(gains.vector, reference, rtol=1e-6, atol=1e-8)
        achieved = np.poly(closed_loop_poles(plant, gains))
        np.testing.assert_allclose(achieved, np.real(np.poly(poles)), atol=1e-8)
        checked += 1


def test_lq_on_random_plants_is_stable_and_optimal(rng):
    for _ in range(20):
        plant = _random_plant(rng)
        try:
            gains = lq_design(plant, LqWeights(1.0, 1.0, 0.1))
        except ConfigurationError:
            continue
        assert np.max(np.abs(closed_loop_poles(plant, gains))) < 1.0


def test_refusals():
    plant = DiscretePlant.integrator(3)
    with pytest.raises(ConfigurationError, match='needs 4 poles'):
        pole_assignment(plant, [0.9, 0.9])
    with pytest.raises(ConfigurationError, match='inside the unit circle'):
        pole_assignment(plant, [1.1, 0.5, 0, 0])
    with pytest.raises(ConfigurationError, match='conjugate pairs'):
        pole_assignment(plant, [0.9 + 0.1j, 0.9 + 0.1j, 0, 0])
    with pytest.raises(ConfigurationError, match='not controllable'):
        # A = (1 - z^-1)(1 - 0.5 z^-1), B = z^-1 (1 - 0.5 z^-1): a common factor.
        pole_assignment(DiscretePlant(a=(-1.5, 0.5), b=(1.0, -0.5)), [0.5, 0.5, 0.5, 0.5])
    with pytest.raises(ConfigurationError, match='at least one sample'):
        DiscretePlant.integrator(0)
    with pytest.raises(ConfigurationError, match='non-zero'):
        DiscretePlant(a=(-1.0,), b=(0.0, 0.0))
    with pytest.raises(ConfigurationError, match='w_u > 0'):
        LqWeights(1.0, 0.0, 1.0)

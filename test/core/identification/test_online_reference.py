"""
The online identifier's scalar update against the equations of methods.md 7.2-7.4 in numpy.

The identifier writes its Kalman step out on Python floats for speed; :class:`NumpyFilter`
below is the same filter as the equations read, in numpy matrices (the form the
identifier had before). Fed the same samples - a wear step that makes the change
detector reset the covariance, outliers, non-finite samples, end stops and command jumps -
the two must take the same decisions sample by sample and end with the same estimate and
covariance to rounding (sums in another order change the last bits only).
"""

from dataclasses import replace
import math

from hydro_sdp.core.identification.online import OnlineSdpIdentifier, OnlineSettings
from hydro_sdp.core.identification.soft_edges import map_and_soft_gradient
from hydro_sdp.core.model.joint_model import JointModel
from hydro_sdp.core.model.simulation import simulate
from hydro_sdp.core.model.static_maps import SdpMap
from hydro_sdp.core.synthetic.programs import random_program
import numpy as np
import pytest

#: The random-walk variance ratios of methods.md 7.2 (a1 .. a6).
NVR = np.array([1e-6, 1e-5, 1e-5, 1e-6, 1e-5, 1e-5])


class NumpyFilter:
    """Methods.md 7.2-7.4 with 6 x 6 numpy matrices: the reference for the scalar update."""

    def __init__(self, model, dt, settings):
        s, c = settings.input_scale, (dt / 0.01) ** 2
        self.model, self.settings = model, settings
        self.delay = model.delay_samples(dt)
        self.theta = np.array(model.alpha(dt))
        self.P0 = np.diag([0.01 * c, 1 / s ** 2, 0.5 * s ** 2, 0.01 * c, 1 / s ** 2, 0.5 * s ** 2])
        self.P = self.P0.copy()
        self.nvr = NVR * np.array([c, 1 / s ** 2, s ** 2, c, 1 / s ** 2, s ** 2])
        self.r = 2.0 * settings.noise_std ** 2
        self.r_min = self.r / 4
        a1, a4 = self.theta[0], self.theta[3]
        low, high = model.static_map.dead_zone
        self.lower = np.array([5 * a1, 0.1 / s, -4 * s * max(1, abs(low)), 0, 0.1 / s, low])
        self.upper = np.array([0, 10 / s, high, 5 * a4, 10 / s, 4 * s * max(1, abs(high))])
        self.commands, self.last_angle, self.quiet = [], None, 0
        self.nis, self.cusum, self.since_reset = 1.0, np.zeros(4), 0
        self.resets = self.updates = 0

    def map_and_gradient(self, u):
        a1, a2, a3, a4, a5, a6 = self.theta
        kappa = self.settings.kappa
        q = a1 * (1 - np.exp(a2 * min(u - a3, 0))) + a4 * (1 - np.exp(-a5 * max(u - a6, 0)))
        below = -kappa * np.logaddexp(0, -(u - a3) / kappa)
        above = kappa * np.logaddexp(0, (u - a6) / kappa)
        e, g = np.exp(a2 * below), np.exp(-a5 * above)
        sigma_below = 1 / (1 + np.exp(min((u - a3) / kappa, 700)))
        sigma_above = 1 / (1 + np.exp(min(-(u - a6) / kappa, 700)))
        return q, np.array([1 - e, -a1 * below * e, a1 * a2 * e * sigma_below,
                            1 - g, a4 * above * g, -a4 * a5 * g * sigma_above])

    def update(self, v, y):
        settings = self.settings
        if not (math.isfinite(v) and math.isfinite(y)):
            self.quiet = settings.hold_off
            return False
        self.commands.append(v)
        previous, self.last_angle = self.last_angle, y
        if previous is None or len(self.commands) < self.delay + 2:
            return False
        u = self.commands[-1 - self.delay]
        if abs(u - self.commands[-2 - self.delay]) > settings.change_gate:
            self.quiet = settings.hold_off
            return False
        if self.quiet > 0:
            self.quiet -= 1
            return False
        stops = self.model.angle_limits
        if (min(y, previous) < stops[0] + settings.margin or
                max(y, previous) > stops[1] - settings.margin):
            return False
        self.P = self.P + np.diag(self.nvr * self.r)
        q, psi = self.map_and_gradient(u)
        eps = (y - previous) - q
        spread = psi @ self.P @ psi
        S = self.r + spread
        z = eps / np.sqrt(S)
        self.nis += (min(z * z, 100) - self.nis) / settings.change_memory
        side = 0 if u < (self.theta[2] + self.theta[5]) / 2 else 2
        z = np.clip(z, -10, 10)
        self.cusum[side] = max(0, self.cusum[side] + z - settings.cusum_drift)
        self.cusum[side + 1] = max(0, self.cusum[side + 1] - z - settings.cusum_drift)
        self.since_reset += 1
        changed = self.cusum.reshape(2, 2).max(axis=1) > settings.cusum_limit
        if self.nis > settings.change_level:
            changed[:] = True
        if changed.any() and self.since_reset > 5 * settings.change_memory:
            forget = np.kron(changed, [0.01, 0.01, 1.0])
            self.P = self.P + self.P0 @ np.diag(forget)
            spread = psi @ self.P @ psi
            S = self.r + spread
            self.nis, self.cusum, self.since_reset = 1.0, np.zeros(4), 0
            self.resets += 1
        elif self.updates > 100 and eps ** 2 > settings.outlier ** 2 * S:
            return False
        K = self.P @ psi / S
        self.theta = np.clip(self.theta + K * eps, self.lower, self.upper)
        self.P = self.P - np.outer(K, psi @ self.P)
        self.r = max(self.r_min, 0.999 * self.r + 0.001 * (eps ** 2 - spread))
        self.updates += 1
        return True


def _samples(model, worn, dt, seconds, seed, v_rest):
    v = random_program(model, dt, seconds, seed=seed, y0=25.0)
    half = v.size // 2
    y1 = simulate(model, v[:half], dt, 25.0, v_before=v_rest)
    y2 = simulate(worn, v[half:], dt, y1[-1], v_before=v[half - 1])
    rng = np.random.default_rng(seed)
    y = np.r_[y1, y2] + rng.normal(0.0, 0.03, v.size)
    # Outliers, lost samples and a stretch pinned near the upper end stop.
    y[rng.choice(np.arange(300, v.size), 6, replace=False)] += 5.0
    v[rng.choice(np.arange(300, v.size), 3, replace=False)] = math.nan
    y[rng.choice(np.arange(300, v.size), 2, replace=False)] = math.inf
    y[half + 400:half + 450] = model.angle_limits[1] - 0.3
    return v, y


VALVE = JointModel('valve', SdpMap(dead_zone=(43.0, 57.0), saturation_velocity=(-29.51, 38.87),
                                   curvature=(0.27, 0.35)),
                   0.15, angle_limits=(-13.8, 63.6), input_limits=(0.0, 100.0))


CASES = ['volts at 100 Hz', 'percent duty at 50 Hz', 'volts, start speeds a sixth of the truth']


@pytest.mark.parametrize('case', CASES)
def test_scalar_update_matches_the_numpy_equations(j2, case):
    if case == 'percent duty at 50 Hz':
        model, dt, v_rest = VALVE, 0.02, 50.0
        worn = replace(VALVE, static_map=replace(VALVE.static_map, dead_zone=(43.0, 54.5)))
        truth = VALVE
    else:
        truth, dt, v_rest = j2, 0.01, 0.0
        worn = replace(j2, static_map=replace(j2.static_map, dead_zone=(-1.05, 1.3124)))
        model = j2
    if case == 'volts, start speeds a sixth of the truth':
        # The speeds' box (a1 >= 5 a1_0, a4 <= 5 a4_0) holds them: the clipping is exercised.
        speeds = tuple(a / 6.0 for a in j2.static_map.saturation_velocity)
        model = replace(j2, static_map=replace(j2.static_map, saturation_velocity=speeds))
    settings = OnlineSettings.for_input_limits(model.input_limits, noise_std=0.03)
    v, y = _samples(truth, worn, dt, 50.0 if dt == 0.01 else 80.0, 3, v_rest)
    scalar, reference = OnlineSdpIdentifier(model, dt, settings), NumpyFilter(model, dt, settings)
    # Coefficients compared on the scale of their start values (an edge may cross zero).
    scale = np.abs(model.alpha(dt))
    decisions, drift, clipped = [], 0.0, 0
    for command, angle in zip(v.tolist(), y.tolist()):
        decisions.append((scalar.update(command, angle), reference.update(command, angle)))
        drift = max(drift, float(np.max(np.abs(scalar.theta - reference.theta) / scale)))
        clipped += np.any((reference.theta == reference.lower) |
                          (reference.theta == reference.upper))
    if case == CASES[2]:
        assert clipped > 100
    assert [new for new, _ in decisions] == [old for _, old in decisions]
    assert scalar.resets == reference.resets >= 1
    assert scalar.updates == reference.updates
    assert 0 < reference.updates < v.size - 100
    # numpy forms P psi in BLAS (fused multiply-adds, another summation order), so the two
    # differ in the last bits, and the correlated covariance (|rho| up to 0.99) carries that
    # on: on these runs up to 1.4e-13 of theta and 4.5e-13 of P (over sqrt(P_ii P_jj)).
    # Moving the numpy filter's own start covariance by one ulp moves it by up to 3.1e-13
    # and 1.9e-12, so the bounds are a few times that, far below any change in the equations.
    assert drift < 1e-12
    covariance_scale = np.sqrt(np.outer(np.diag(reference.P), np.diag(reference.P)))
    np.testing.assert_allclose(scalar.P / covariance_scale, reference.P / covariance_scale,
                               rtol=0, atol=5e-12)
    np.testing.assert_allclose(scalar.standard_errors, np.sqrt(np.diag(reference.P)),
                               rtol=5e-12)
    assert scalar.r == pytest.approx(reference.r, rel=1e-12)
    assert scalar.nis == pytest.approx(reference.nis, rel=1e-12)


def test_the_per_sample_map_is_eq_5_as_the_map_family_codes_it(j2):
    # soft_edges writes eq. (5) out on floats for the per-sample path: its value is the
    # map's own rate, and away from the soft edges its gradient is that of the map's own
    # eq. (5) in the paper's coefficients (central differences of SdpMap.from_alpha).
    dt, kappa = 0.01, 0.005
    theta = list(j2.alpha(dt))
    low, high = j2.dead_zone
    commands = np.r_[np.linspace(-5.0, low - 0.2, 7), np.linspace(high + 0.2, 5.0, 7),
                     np.linspace(low + 0.1, high - 0.1, 3)]
    for u in commands:
        q, gradient = map_and_soft_gradient(float(u), theta, kappa)
        assert q == pytest.approx(float(j2.rate(u)) * dt, rel=1e-12, abs=1e-15)
        for index in range(6):
            step = 1e-6 * max(1.0, abs(theta[index]))
            moved = [list(theta), list(theta)]
            moved[0][index] += step
            moved[1][index] -= step
            rates = [SdpMap.from_alpha(tuple(m), dt).rate(np.array([u]))[0] * dt for m in moved]
            assert gradient[index] == pytest.approx((rates[0] - rates[1]) / (2 * step),
                                                    rel=1e-5, abs=1e-8), (u, index)

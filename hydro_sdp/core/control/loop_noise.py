"""How the angle sensor's noise reaches the PIP controller's output ``u`` (methods 5.5)."""

from __future__ import annotations

from hydro_sdp.core.control.pip_design import closed_loop_poles, DiscretePlant, PipGains
import numpy as np

#: Most doubling passes of the Gramian's sum (2^64 terms).
DOUBLINGS = 64


def noise_gain(plant: DiscretePlant, gains: PipGains) -> float:
    """Return the standard deviation of ``u`` per degree of white noise on the measured angle."""
    denominator = np.real(np.poly(closed_loop_poles(plant, gains)))
    delta = np.array([1.0, -1.0])
    feedback = np.convolve(delta, np.asarray(gains.f, dtype=np.float64))
    feedback[0] += gains.k_i
    numerator = -np.convolve(feedback, np.r_[1.0, plant.a])
    order = max(numerator.size, denominator.size)
    b = np.pad(numerator, (0, order - numerator.size)) / denominator[0]
    a = np.pad(denominator, (0, order - denominator.size)) / denominator[0]
    direct = b[0]
    if order == 1:
        return abs(float(direct))
    # Controllable canonical form of b(z^-1) / a(z^-1): h_0 = d, h_k = c A^(k-1) e_1.
    states = order - 1
    transition = np.zeros((states, states))
    transition[0, :] = -a[1:]
    transition[1:, :-1] = np.eye(states - 1)
    output = b[1:] - direct * a[1:]
    # P = sum_k A^k e_1 e_1' A'^k by doubling (Smith): each pass adds as many terms as it
    # has, so a pole at 0.9999 takes about twenty passes, and any delay stays cheap.
    gramian = np.zeros((states, states))
    gramian[0, 0] = 1.0
    power = transition
    for _ in range(DOUBLINGS):
        added = power @ gramian @ power.T
        gramian = gramian + added
        if np.max(np.abs(added)) <= 1e-17 * np.max(np.abs(gramian)):
            break
        power = power @ power
    return float(np.sqrt(direct ** 2 + output @ gramian @ output))

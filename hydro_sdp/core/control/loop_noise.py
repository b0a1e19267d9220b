"""
How the angle sensor's noise reaches the PIP controller's output ``u``.

With the measured angle ``y + e``, the incremental PIP law (docs/methods.md
section 4.2) and the design plant ``A y = B u`` give

``u / e = -(F(z^-1) Delta + k_I) A / (Delta (A G + B F) + k_I B)``

whose denominator is the closed-loop polynomial of section 4.3. For white
noise of standard deviation ``sigma`` the standard deviation of ``u`` is
``sigma`` times the root of the sum of the squared impulse response: the
:func:`noise_gain`. An IDZ chatter band a few times that wide keeps the valve
from reversing on noise alone (section 5.4).

"""

from __future__ import annotations

import math

from hydro_sdp.core.control.pip_design import closed_loop_poles, DiscretePlant, PipGains
import numpy as np

#: Impulse response kept until it has decayed to this fraction.
DECAY = 1e-9


def noise_gain(plant: DiscretePlant, gains: PipGains) -> float:
    """
    Return the standard deviation of ``u`` per degree of white noise on the measured angle.

    Parameters
    ----------
    plant : DiscretePlant
        The design plant.
    gains : PipGains
        The PIP gains (a stable closed loop).

    Returns
    -------
    float
        ``sqrt(sum h_k^2)`` of the impulse response ``h`` from the noise to ``u``.

    """
    from scipy.signal import lfilter   # here: importing scipy.signal takes seconds
    poles = closed_loop_poles(plant, gains)
    denominator = np.real(np.poly(poles))
    delta = np.array([1.0, -1.0])
    feedback = np.convolve(delta, np.asarray(gains.f, dtype=np.float64))
    feedback[0] += gains.k_i
    numerator = -np.convolve(feedback, np.r_[1.0, plant.a])
    largest = float(np.max(np.abs(poles)))
    samples = 64 if largest < 1e-6 else int(
        min(200000, max(64, math.ceil(math.log(DECAY) / math.log(largest)) * 2)))
    impulse = np.zeros(samples)
    impulse[0] = 1.0
    response = lfilter(numerator, denominator, impulse)
    return float(np.sqrt(np.sum(response ** 2)))

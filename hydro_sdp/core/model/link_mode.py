"""The link's mode on the oil column (effect ``oscillation``), exact per sample (methods 3.6)."""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
import math

from hydro_sdp.core.arrays import FloatArray
from hydro_sdp.core.errors import DataError
from hydro_sdp.core.model.effects import Oscillation
from hydro_sdp.core.model.timing import SamplePeriod
import numpy as np


@dataclass(frozen=True)
class LinkMode:
    """
    The mode's zero-order hold at one sample period.

    Parameters
    ----------
    transition : tuple[float, float, float, float]
        ``P`` row by row.
    input_gain : tuple[float, float]
        ``G``.
    lead : float
        ``2 d / w_n``, s: how far a settled link trails the actuator per deg/s.

    """

    transition: tuple[float, float, float, float]
    input_gain: tuple[float, float]
    lead: float

    @classmethod
    def of(cls, effect: Oscillation, dt: SamplePeriod) -> LinkMode:
        """Return the mode of ``effect`` at ``dt`` s (its frequency below the Nyquist one)."""
        if not effect.frequency < 0.5 / dt:
            raise DataError(f'the oscillation at {effect.frequency:g} Hz is not below the '
                            f'Nyquist frequency of the sample period {dt:g} s '
                            f'({0.5 / dt:g} Hz)')
        w = 2.0 * math.pi * effect.frequency
        sigma = effect.damping * w
        wd = w * math.sqrt(1.0 - effect.damping ** 2)
        decay, c, s = math.exp(-sigma * dt), math.cos(wd * dt), math.sin(wd * dt)
        p = (decay * (c + sigma / wd * s), decay * s / wd,
             -decay * w * w / wd * s, decay * (c - sigma / wd * s))
        # G = A^-1 (P - I) [-1, 0]', A^-1 = [[-2 d / w, -1 / w^2], [1, 0]].
        first, second = 1.0 - p[0], -p[2]
        gain = (-2.0 * effect.damping / w * first - second / (w * w), first)
        return cls(p, gain, 2.0 * effect.damping / w)

    def settled(self, speed: float) -> tuple[float, float]:
        """Return the state ``(e, u)`` of a link moving steadily at ``speed`` deg/s."""
        return -self.lead * speed, speed

    def deviation(self, speeds: FloatArray, before: float) -> FloatArray:
        """Return ``e_k = y_k - x_k``, deg, for actuator speeds ``w_k``, settled at ``before``."""
        return self.states(speeds, before)[0]

    def states(self, speeds: FloatArray, before: float) -> tuple[FloatArray, FloatArray]:
        """Return ``e_k`` and the link's speed ``u_k`` after each interval (:meth:`deviation`)."""
        w = np.asarray(speeds, dtype=np.float64)
        if w.size == 0:
            return np.zeros(0), np.zeros(0)
        pole, column, row = self.modal
        # Modal coordinates: m_k = pole m_{k-1} + g w_k, and e = 2 Re(V[0, 0] m).
        gain = row[0] * self.input_gain[0] + row[1] * self.input_gain[1]
        settled = self.settled(before)
        state = row[0] * settled[0] + row[1] * settled[1]
        # The recursion as a first-order filter in C; imported here, as the light command
        # paths (identify) never need it.
        from scipy.signal import lfilter
        out = lfilter([gain], [1.0, -pole], w.astype(np.complex128), zi=[pole * state])[0]
        return 2.0 * (column[0] * out).real, 2.0 * (column[1] * out).real

    @cached_property
    def modal(self) -> tuple[complex, tuple[complex, complex], tuple[complex, complex]]:
        """Return a pole of ``P``, its eigenvector and the matching row of the inverse."""
        p00, p01, p10, p11 = self.transition
        half = 0.5 * (p00 + p11)
        spread = (p00 * p11 - p01 * p10) - half * half
        if not (spread > 0.0 and p01 != 0.0):
            # Not a ringing pair (a mode this package builds always is): numpy's answer.
            poles, vectors = np.linalg.eig(np.array([[p00, p01], [p10, p11]]))
            inverse = np.linalg.inv(vectors)
            return (complex(poles[0]), (complex(vectors[0, 0]), complex(vectors[1, 0])),
                    (complex(inverse[0, 0]), complex(inverse[0, 1])))
        # The pair lambda, conj(lambda) with eigenvectors (p01, lambda - p00): the 2 x 2
        # in closed form, without two LAPACK calls per simulated run.
        pole = complex(half, math.sqrt(spread))
        other = pole.conjugate()
        scale = p01 * (other - pole)
        return pole, (complex(p01), pole - p00), ((other - p00) / scale, -p01 / scale)

    def ring(self, x: FloatArray, dt: SamplePeriod, before: float) -> FloatArray:
        """Return the link's angles for the actuator's angles ``x`` (first one settled)."""
        x = np.asarray(x, dtype=np.float64)
        if x.size < 2:
            return x.copy()
        e = self.deviation(np.diff(x) / dt, before)
        return np.r_[x[0] + self.settled(before)[0], x[1:] + e]


class LinkState:
    """The mode stepped one sample at a time (the same equations as :class:`LinkMode`)."""

    def __init__(self, mode: LinkMode, speed: float,
                 state: tuple[float, float] | None = None) -> None:
        self.mode = mode
        self.e, self.u = mode.settled(speed) if state is None else state

    def step(self, speed: float) -> float:
        """Advance over an interval of actuator speed ``speed``; return ``e = y - x``."""
        p00, p01, p10, p11 = self.mode.transition
        g0, g1 = self.mode.input_gain
        e, u = self.e, self.u
        self.e = p00 * e + p01 * u + g0 * speed
        self.u = p10 * e + p11 * u + g1 * speed
        return self.e

"""The plant a PIP-IDZ design sees: the integrator, dead time and valve lag (methods 4.1)."""

from __future__ import annotations

import cmath
import math
from typing import Sequence

from hydro_sdp.core.control.pip_design import DiscretePlant
from hydro_sdp.core.errors import ConfigurationError
from hydro_sdp.core.model.effects import Oscillation, ValveLag
from hydro_sdp.core.model.joint_model import JointModel
from hydro_sdp.core.model.timing import SamplePeriod
import numpy as np

#: Relative tolerance when a controller file's plant is checked against its valve lag.
PLANT_TOLERANCE = 1e-9


#: A link mode of the design plant: frequency, Hz, and damping ratio.
Mode = tuple[float, float]


def lagged_integrator(delay: int, time_constant: float | None,
                      control_period: SamplePeriod, mode: Mode | None = None) -> DiscretePlant:
    """
    Return the integrator behind ``delay`` control samples, a first-order lag and a mode.

    ``delay``: delay in control samples (>= 1), as :meth:`DiscretePlant.integrator`.
    ``time_constant``: lag time constant, s (``None``: no lag, the plain integrator).
    ``control_period``: control period, s.
    ``mode``: the link's mode, frequency (Hz) and damping ratio (``None``: none).
    Returns: ``n`` = 1, plus 1 with the lag, plus 2 with the mode; ``m = delay + n - 1``.
    """
    if time_constant is not None and not (math.isfinite(time_constant)
                                          and time_constant > 0.0):
        raise ConfigurationError(f'the valve lag must be a time constant > 0 s, '
                                 f'got {time_constant}')
    if mode is not None:
        return _with_mode(delay, time_constant, control_period, mode)
    if time_constant is None:
        return DiscretePlant.integrator(delay)
    if delay < 1:
        raise ConfigurationError(f'the delay must be at least one sample, got {delay}')
    p = math.exp(-control_period / time_constant)
    ratio = time_constant / control_period
    b1 = 1.0 - ratio * (1.0 - p)
    b2 = ratio * (1.0 - p) - p
    return DiscretePlant(a=(-(1.0 + p), p), b=(0.0,) * (delay - 1) + (b1, b2))


def _with_mode(delay: int, time_constant: float | None, period: SamplePeriod,
               mode: Mode) -> DiscretePlant:
    """Return the zero-order hold of ``1 / (T s)``, the lag and the mode, behind the delay."""
    frequency, damping = mode
    if not (math.isfinite(frequency) and 0.0 < frequency < 0.5 / period
            and 0.0 < damping < 1.0):
        raise ConfigurationError(f'the mode must have a frequency above 0 and below the '
                                 f'Nyquist frequency ({0.5 / period:g} Hz) and a damping '
                                 f'ratio inside (0, 1), got {frequency} Hz and {damping}')
    if delay < 1:
        raise ConfigurationError(f'the delay must be at least one sample, got {delay}')
    w = 2.0 * math.pi * frequency
    sigma, wd = damping * w, w * math.sqrt(1.0 - damping * damping)
    poles = [0j, complex(-sigma, wd), complex(-sigma, -wd)]
    gain = w * w / period
    if time_constant is not None:
        poles.append(complex(-1.0 / time_constant))
        gain /= time_constant
    discrete = [cmath.exp(pole * period) for pole in poles]
    a = np.array([1.0 + 0j])
    for z in discrete:
        a = np.convolve(a, [1.0, -z])
    b = np.zeros(len(poles), dtype=complex)
    for i, pole in enumerate(poles):
        residue = gain / np.prod([pole - other for j, other in enumerate(poles) if j != i])
        held = residue * period if pole == 0 else residue * (discrete[i] - 1.0) / pole
        rest = np.array([1.0 + 0j])
        for j, z in enumerate(discrete):
            if j != i:
                rest = np.convolve(rest, [1.0, -z])
        b += held * rest
    return DiscretePlant(a=tuple(float(x) for x in a.real[1:]),
                         b=(0.0,) * (delay - 1) + tuple(float(x) for x in b.real))


def mode_poles(mode: Mode, control_period: SamplePeriod) -> tuple[complex, complex]:
    """Return the mode's pair of poles at the control period, ``exp((-d w +- i w_d) T)``."""
    frequency, damping = mode
    w = 2.0 * math.pi * frequency
    pole = cmath.exp(complex(-damping * w, w * math.sqrt(1.0 - damping * damping))
                     * control_period)
    return pole, pole.conjugate()


def model_mode(model: JointModel) -> Mode | None:
    """Return the frequency (Hz) and damping of the model's ``oscillation``, or ``None``."""
    mode = model.effect(Oscillation.name)
    return (mode.frequency, mode.damping) if isinstance(mode, Oscillation) else None


def model_lag(model: JointModel) -> float | None:
    """Return the time constant of the model's ``valve_lag``, s, or ``None``."""
    lag = model.effect(ValveLag.name)
    return lag.time_constant if isinstance(lag, ValveLag) else None


def plant_for_model(model: JointModel, control_period: SamplePeriod) -> DiscretePlant:
    """Return the design plant of a model: its delay and its valve lag at the control period."""
    return lagged_integrator(model.delay_samples(control_period), model_lag(model),
                             control_period, model_mode(model))


def completed_poles(plant: DiscretePlant, poles: Sequence[complex]) -> list[complex]:
    """Complete dominant ``poles`` to the ``n + m`` a plant needs."""
    wanted = [complex(p) for p in poles]
    size = plant.n + plant.m
    if plant.n == 2 and len(wanted) < size:
        wanted.append(complex(plant.a[1]))     # A = (1 - z^-1)(1 - p z^-1): a_2 = p
    elif plant.n > 2:
        # A = (1 - z^-1) times the lag's and the mode's factors: keep their roots.
        own = np.polydiv(np.r_[1.0, plant.a], [1.0, -1.0])[0]
        wanted += [complex(p) for p in np.roots(own)][:max(0, size - len(wanted))]
    return wanted + [0j] * max(0, size - len(wanted))


def check_plant_lag(plant: DiscretePlant, time_constant: float | None,
                    control_period: SamplePeriod, mode: Mode | None = None) -> None:
    """
    Raise :class:`ConfigurationError` unless ``plant`` is the integrator of its lag and mode.

    ``plant``: a controller file's plant.
    ``time_constant``: the valve lag the file says the plant was made from, s.
    ``control_period``: the file's control period, s.
    ``mode``: the link's mode the file says the plant was made from, Hz and damping ratio.
    """
    expected = lagged_integrator(plant.delay, time_constant, control_period, mode)
    same = (len(expected.a) == len(plant.a) and len(expected.b) == len(plant.b)
            and all(math.isclose(x, y, rel_tol=PLANT_TOLERANCE, abs_tol=1e-12)
                    for x, y in zip(expected.a + expected.b, plant.a + plant.b)))
    if not same:
        ringing = '' if mode is None else f' and a mode of {mode[0]} Hz, damping {mode[1]}'
        raise ConfigurationError(
            f'the plant (a {list(plant.a)}, b {list(plant.b)}) is not the integrator with '
            f'{plant.delay} samples of delay and a valve lag of {time_constant} s{ringing} at '
            f'{control_period} s (a {list(expected.a)}, b {list(expected.b)})')

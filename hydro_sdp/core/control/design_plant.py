"""
The plant a PIP-IDZ design sees: the integrator with the model's dead time and valve lag.

With the IDZ inverting the static map, the joint seen from the controller's
``u`` (degrees per control sample) is an integrator of unit gain behind the
model's pure delay and, when the model has a ``valve_lag`` effect, its
first-order lag (docs/methods.md section 4.1). With a zero-order hold at the
control period ``T`` and ``p = exp(-T / T_v)`` the lagged integrator
``1 / (T s (T_v s + 1))`` is exactly

``A = (1 - z^-1)(1 - p z^-1)``, ``B = z^-(tau - 1) (b_1 z^-1 + b_2 z^-2)``

with ``b_1 = 1 - r (1 - p)``, ``b_2 = r (1 - p) - p`` and ``r = T_v / T``; it
becomes ``A = 1 - z^-1``, ``B = z^-tau`` as the lag goes to 0. ``tau`` is the
model's delay in control samples.

"""

from __future__ import annotations

import math
from typing import Sequence

from hydro_sdp.core.control.pip_design import DiscretePlant
from hydro_sdp.core.errors import ConfigurationError
from hydro_sdp.core.model.effects import ValveLag
from hydro_sdp.core.model.joint_model import JointModel
from hydro_sdp.core.model.timing import check_sample_period

#: Relative tolerance when a controller file's plant is checked against its valve lag.
PLANT_TOLERANCE = 1e-9


def lagged_integrator(delay: int, time_constant: float | None,
                      control_period: float) -> DiscretePlant:
    """
    Return the integrator behind ``delay`` control samples and a first-order lag.

    Parameters
    ----------
    delay : int
        Delay in control samples (>= 1), as :meth:`DiscretePlant.integrator`.
    time_constant : float or None
        Lag time constant, s (``None``: no lag, the plain integrator).
    control_period : float
        Control period, s.

    Returns
    -------
    DiscretePlant
        ``n = 2`` and ``m = delay + 1`` with the lag, else ``n = 1``, ``m = delay``.

    """
    period = check_sample_period(control_period)
    if time_constant is None:
        return DiscretePlant.integrator(delay)
    if not (math.isfinite(time_constant) and time_constant > 0.0):
        raise ConfigurationError(f'the valve lag must be a time constant > 0 s, '
                                 f'got {time_constant}')
    if delay < 1:
        raise ConfigurationError(f'the delay must be at least one sample, got {delay}')
    p = math.exp(-period / time_constant)
    ratio = time_constant / period
    b1 = 1.0 - ratio * (1.0 - p)
    b2 = ratio * (1.0 - p) - p
    return DiscretePlant(a=(-(1.0 + p), p), b=(0.0,) * (delay - 1) + (b1, b2))


def model_lag(model: JointModel) -> float | None:
    """Return the time constant of the model's ``valve_lag``, s, or ``None``."""
    lag = model.effect(ValveLag.name)
    return lag.time_constant if isinstance(lag, ValveLag) else None


def plant_for_model(model: JointModel, control_period: float) -> DiscretePlant:
    """
    Return the design plant of a model: its delay and its valve lag at the control period.

    Parameters
    ----------
    model : JointModel
        The joint.
    control_period : float
        Control period, s.

    Returns
    -------
    DiscretePlant
        :func:`lagged_integrator` of the model's delay in control samples and lag.

    """
    period = check_sample_period(control_period)
    return lagged_integrator(model.delay_samples(period), model_lag(model), period)


def completed_poles(plant: DiscretePlant, poles: Sequence[complex]) -> list[complex]:
    """
    Complete dominant ``poles`` to the ``n + m`` a plant needs.

    A lagged integrator (``n = 2``) keeps its lag pole ``p`` (the valve is not
    made faster, which would take large gains and amplify the noise); the
    remaining poles are deadbeat (at 0). Extra poles beyond ``n + m`` are refused
    by the design, not here.

    Parameters
    ----------
    plant : DiscretePlant
        The design plant.
    poles : sequence of complex
        The poles asked for, the dominant ones.

    Returns
    -------
    list of complex
        ``poles``, then the lag pole (if room), then zeros.

    """
    wanted = [complex(p) for p in poles]
    size = plant.n + plant.m
    if plant.n == 2 and len(wanted) < size:
        wanted.append(complex(plant.a[1]))     # A = (1 - z^-1)(1 - p z^-1): a_2 = p
    return wanted + [0j] * max(0, size - len(wanted))


def check_plant_lag(plant: DiscretePlant, time_constant: float | None,
                    control_period: float) -> None:
    """
    Raise :class:`ConfigurationError` unless ``plant`` is the lagged integrator of its lag.

    Parameters
    ----------
    plant : DiscretePlant
        A controller file's plant.
    time_constant : float or None
        The valve lag the file says the plant was made from, s.
    control_period : float
        The file's control period, s.

    """
    expected = lagged_integrator(plant.delay, time_constant, control_period)
    same = (len(expected.a) == len(plant.a) and len(expected.b) == len(plant.b)
            and all(math.isclose(x, y, rel_tol=PLANT_TOLERANCE, abs_tol=1e-12)
                    for x, y in zip(expected.a + expected.b, plant.a + plant.b)))
    if not same:
        raise ConfigurationError(
            f'the plant (a {list(plant.a)}, b {list(plant.b)}) is not the integrator with '
            f'{plant.delay} samples of delay and a valve lag of {time_constant} s at '
            f'{control_period} s (a {list(expected.a)}, b {list(expected.b)})')

"""
The nominal sample period of time stamps written by a real timer (methods 3.4).

The median spacing rounded to the digits the stamps support; the control period is a
whole multiple of it (:func:`control_period_on`).
"""

from __future__ import annotations

from dataclasses import dataclass
import math

from hydro_sdp.core.arrays import FloatArray, IntArray
from hydro_sdp.core.errors import ConfigurationError, DataError
from hydro_sdp.core.model.timing import SamplePeriod
import numpy as np

#: Uncertainty of a period below which it is taken as exact, relative (100 ppm).
RELATIVE_FLOOR = 1e-4
#: Standard errors of the median a rounded period may lie from it.
STANDARD_ERRORS = 3.0
#: Most significant digits a nominal period keeps.
MOST_DIGITS = 12
#: Largest relative distance of a controller's period from a whole number of plant
#: samples, when both are given (1 %: timers and clocks are far closer).
PERIOD_TOLERANCE = 0.01


def nominal_period(steps: FloatArray | IntArray) -> float:
    """
    Return the nominal period of spacings between time stamps (their unit).

    ``steps``: spacings of successive stamps (seconds, or integer nanoseconds), > 0.
    Raises DataError when there is no spacing, or the median is not a positive finite number.
    """
    spacings = np.asarray(steps, dtype=np.float64)
    if spacings.size == 0:
        raise DataError('needs at least two time stamps for a sample period')
    median = float(np.median(spacings))
    if not (math.isfinite(median) and median > 0.0):
        raise DataError(f'the time stamps give no positive sample period (median spacing '
                        f'{median!r})')
    regular = spacings[np.abs(spacings - median) < 0.5 * median]
    spread = 1.4826 * float(np.median(np.abs(regular - median))) if regular.size else 0.0
    standard_error = 1.2533 * spread / math.sqrt(max(regular.size, 1))
    tolerance = max(STANDARD_ERRORS * standard_error, RELATIVE_FLOOR * median)
    return round_within(median, tolerance)


def round_within(value: float, tolerance: float) -> float:
    """Round a positive ``value`` to the fewest significant digits within ``tolerance`` (>= 0)."""
    for digits in range(1, MOST_DIGITS + 1):
        rounded = float(f'{value:.{digits}g}')
        if abs(rounded - value) <= tolerance:
            return rounded
    return value


def period_of_stamps(t: FloatArray | IntArray) -> float:
    """Return :func:`nominal_period` of increasing time stamps ``t`` (at least two; their unit)."""
    return nominal_period(np.diff(np.asarray(t)))


def whole_samples_seconds(samples: int, dt: float) -> float:
    """Return ``samples`` periods of ``dt`` in seconds (``12 x 0.01`` is ``0.12``)."""
    digits = len(f'{dt:.{MOST_DIGITS}g}'.replace('.', '').lstrip('0').split('e')[0])
    return float(f'{samples * dt:.{digits + len(str(abs(int(samples))))}g}')


@dataclass(frozen=True)
class ControlPeriod:
    """
    A control period as a whole number of plant samples.

    Parameters
    ----------
    samples : int
        Plant samples per control step, >= 1.
    seconds : SamplePeriod
        The period, ``samples`` plant periods (written cleanly), s.
    asked : float
        The period asked for, s.

    """

    samples: int
    seconds: SamplePeriod
    asked: float


def control_period_on(asked: float, dt: SamplePeriod) -> ControlPeriod:
    """Return the whole multiple of the plant period nearest the control period asked for."""
    samples = max(1, int(math.floor(asked / dt + 0.5 + 1e-9)))
    return ControlPeriod(samples, SamplePeriod(whole_samples_seconds(samples, dt)), float(asked))


def control_steps(control_period: SamplePeriod, dt: SamplePeriod) -> int:
    """Return the plant samples per control step of a controller run on a plant."""
    period = control_period_on(control_period, dt)
    ratio = control_period / dt
    if abs(ratio - period.samples) > PERIOD_TOLERANCE * period.samples:
        raise ConfigurationError(
            f'the control period {control_period:.9g} s must be a whole multiple of the plant '
            f'period {dt:.9g} s (within {PERIOD_TOLERANCE:.0%}; it is {ratio:.4g} periods)')
    return period.samples

"""
Timing: the checked sample period, the command in force at each sample, delays (methods 3.4).

``v_k`` is the command in force over ``(t_{k-1}, t_k]``: in a bag, the last one
received before ``t_k``.
"""

from __future__ import annotations

from collections import deque
import math
import numbers

from hydro_sdp.core.arrays import FloatArray, IntArray
from hydro_sdp.core.errors import ConfigurationError, ModelFileError
from hydro_sdp.core.validation import require_float
import numpy as np


class SamplePeriod(float):
    """
    A sample period, s: a finite number > 0, checked once, where it enters the core.

    The period of a record's samples (``dt``) or of a controller's steps
    (``control_period``). Functions of the core take it and do not check it again;
    arithmetic on it gives a plain float, to be wrapped again where it is a period.

    Raises
    ------
    ConfigurationError
        When ``seconds`` is not a finite number > 0.

    """

    __slots__ = ()

    def __new__(cls, seconds: float) -> SamplePeriod:
        if type(seconds) is cls:
            return seconds
        if not (isinstance(seconds, numbers.Real) and not isinstance(seconds, bool)
                and math.isfinite(seconds) and seconds > 0.0):
            raise ConfigurationError(
                f'sample period must be a positive number of seconds, got {seconds!r}')
        return super().__new__(cls, seconds)

    def __repr__(self) -> str:
        return float.__repr__(self)


def require_period(value: object, key: str) -> SamplePeriod:
    """Return ``value`` as a :class:`SamplePeriod`, or raise naming the dotted ``key``."""
    try:
        return SamplePeriod(require_float(value, key))
    except ConfigurationError as error:
        raise ModelFileError(f'key {key!r}: {error}') from None


def delay_samples(delay: float, dt: SamplePeriod) -> int:
    """Convert a delay (s) to whole samples at period ``dt`` (nearest, ties up, at least one)."""
    # The small tolerance keeps 0.15 / 0.05 = 2.9999999999999996 at 3.
    return max(1, int(math.floor(delay / dt + 0.5 + 1e-9)))


def delayed(values: FloatArray, tau: int, before: float | None = None) -> FloatArray:
    """
    Shift a per-sample sequence ``tau`` samples later: element ``k`` is ``values[k - tau]``.

    ``tau``: delay, samples (>= 0).
    ``before``: value in force before the sequence starts; None: its first value.
    """
    values = np.asarray(values, dtype=np.float64)
    if tau < 0:
        raise ConfigurationError(f'delay must be >= 0 samples, got {tau}')
    out = np.empty_like(values)
    if values.size == 0:
        return out
    head = min(tau, values.size)
    out[:head] = values[0] if before is None else before
    out[head:] = values[:values.size - head]
    return out


def delayed_at(values: FloatArray, indices: IntArray, tau: int) -> FloatArray:
    """
    ``values[k - tau]`` at the sample indices ``k``, holding the first value before the start.

    ``values``: per-sample commands of one record.
    """
    return np.asarray(values)[np.maximum(np.asarray(indices) - tau, 0)]


def command_in_force(sample_stamps: FloatArray | IntArray,
                     command_stamps: FloatArray | IntArray) -> IntArray:
    """Index of the command in force at each sample: the last one received strictly before it."""
    return np.searchsorted(command_stamps, sample_stamps, side='left') - 1


def command_stamps_for(sample_stamps: IntArray) -> IntArray:
    """Stamps (ns) at which to write the commands ``v_k`` of samples ``t_k`` to read back."""
    stamps = np.asarray(sample_stamps, dtype=np.int64)
    return np.r_[2 * stamps[0] - stamps[1], stamps[:-1]]


class DelayLine:
    """
    The last ``tau + 1`` values pushed, one per sample: what a pure delay holds.

    ``tau``: longest delay to be asked for, samples.
    """

    def __init__(self, tau: int, before: float) -> None:
        if tau < 0:
            raise ConfigurationError(f'delay must be >= 0 samples, got {tau}')
        self._values: deque[float] = deque([float(before)] * (tau + 1), maxlen=tau + 1)

    def push(self, value: float) -> None:
        """Add the newest value."""
        self._values.append(float(value))

    def delayed(self, tau: int) -> float:
        """Return the value ``tau`` samples before the newest (``v_{k-tau}``)."""
        return self._values[-1 - tau]

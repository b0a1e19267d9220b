"""
Timing: which command is in force at each sample, and how delay is counted.

One rule runs through the whole package (docs/methods.md section 3.4):
``v_k`` is the command in force over the interval ``(t_{k-1}, t_k]`` that ends at
sample ``t_k``: in a bag, the last command received *before* ``t_k``; in a loop,
the answer a controller gave to ``y_{k-1}``. A pure delay of ``tau`` samples
makes the speed over that interval depend on ``v_{k-tau}``. Everything that
pairs commands with samples (simulation, bag reader and writer, closed loop,
nodes, online update, identification, diagnosis) calls this module.

"""

from __future__ import annotations

from collections import deque
import math

from hydro_sdp.core.arrays import FloatArray, IntArray
from hydro_sdp.core.errors import ConfigurationError
import numpy as np


def check_sample_period(dt: float) -> float:
    """
    Return ``dt`` if it is a usable sample period, else raise :class:`ConfigurationError`.

    Parameters
    ----------
    dt : float
        Sample period, s.

    Returns
    -------
    float
        The same period.

    """
    if not (isinstance(dt, (int, float)) and math.isfinite(dt) and dt > 0.0):
        raise ConfigurationError(f'sample period must be a positive number of seconds, got {dt!r}')
    return float(dt)


def delay_samples(delay: float, dt: float) -> int:
    """
    Convert a delay in seconds to whole samples at period ``dt`` (nearest, ties up).

    The papers count the delay from issuing a command to the first sample that
    shows its motion, so it is at least one sample: a command issued at ``t_k``
    can move the joint in the interval ending at ``t_{k+1}`` at the earliest.

    Parameters
    ----------
    delay : float
        Pure time delay, s.
    dt : float
        Sample period, s.

    Returns
    -------
    int
        Delay in samples.

    """
    check_sample_period(dt)
    # The small tolerance keeps 0.15 / 0.05 = 2.9999999999999996 at 3.
    return max(1, int(math.floor(delay / dt + 0.5 + 1e-9)))


def delayed(values: FloatArray, tau: int, before: float | None = None) -> FloatArray:
    """
    Shift a per-sample sequence ``tau`` samples later: element ``k`` is ``values[k - tau]``.

    Parameters
    ----------
    values : FloatArray
        Per-sample values (commands, or the speeds they give).
    tau : int
        Delay, samples (>= 0).
    before : float or None
        Value in force before the sequence starts; default: its first value
        (the command held from before the record began).

    Returns
    -------
    FloatArray
        The delayed sequence, same length.

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

    Parameters
    ----------
    values : FloatArray
        Per-sample commands of one record.
    indices : IntArray
        Sample indices ``k`` into ``values``.
    tau : int
        Delay, samples.

    Returns
    -------
    FloatArray
        The delayed commands at ``indices``.

    """
    return np.asarray(values)[np.maximum(np.asarray(indices) - tau, 0)]


def command_in_force(sample_stamps: FloatArray | IntArray,
                     command_stamps: FloatArray | IntArray) -> IntArray:
    """
    Index of the command in force at each sample: the last one received before it.

    A command stamped exactly at a sample is not yet in force there (it answers
    that sample). ``command_stamps`` must be sorted.

    Parameters
    ----------
    sample_stamps : array
        Time of each sample (any unit, same as ``command_stamps``).
    command_stamps : array
        Time of each command, sorted.

    Returns
    -------
    IntArray
        Index into the commands per sample; -1 where no command came before.

    """
    return np.searchsorted(command_stamps, sample_stamps, side='left') - 1


def command_stamps_for(sample_stamps: IntArray) -> IntArray:
    """
    Stamps at which to write the commands ``v_k`` of samples ``t_k`` so they read back.

    ``v_k`` is in force over the interval ending at ``t_k``, so it is written at
    ``t_{k-1}`` (the first one a period before ``t_0``), when a controller reading
    ``y_{k-1}`` would have sent it; :func:`command_in_force` then pairs it with
    ``t_k`` again.

    Parameters
    ----------
    sample_stamps : IntArray
        Sample stamps, ns (at least two, increasing).

    Returns
    -------
    IntArray
        Command stamps, ns.

    """
    stamps = np.asarray(sample_stamps, dtype=np.int64)
    return np.r_[2 * stamps[0] - stamps[1], stamps[:-1]]


class DelayLine:
    """
    The last ``tau + 1`` values pushed, one per sample: what a pure delay holds.

    Pushing ``v_k`` makes :attr:`current` the newest value and
    :meth:`delayed` return ``v_{k-tau}`` (or the value in force before the first
    push while the line is filling).

    Parameters
    ----------
    tau : int
        Longest delay to be asked for, samples.
    before : float
        Value in force before the first push.

    """

    def __init__(self, tau: int, before: float) -> None:
        if tau < 0:
            raise ConfigurationError(f'delay must be >= 0 samples, got {tau}')
        self._values: deque[float] = deque([float(before)] * (tau + 1), maxlen=tau + 1)

    def push(self, value: float) -> None:
        """
        Add the newest value.

        Parameters
        ----------
        value : float
            Value of the new sample.

        """
        self._values.append(float(value))

    def delayed(self, tau: int) -> float:
        """
        Return the value ``tau`` samples before the newest.

        Parameters
        ----------
        tau : int
            Delay, samples (at most the line's length).

        Returns
        -------
        float
            ``v_{k-tau}``.

        """
        return self._values[-1 - tau]

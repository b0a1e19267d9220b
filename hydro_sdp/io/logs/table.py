"""
A logger's file as channels, each with its own time base, and the rule that aligns them.

Reasoning: methods 3.4.

"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

from hydro_sdp.core.arrays import FloatArray, IntArray
from hydro_sdp.core.errors import DataError
import numpy as np


@dataclass(frozen=True, eq=False)
class Channel:
    """
    One logged signal.

    Attributes
    ----------
    t : FloatArray
        Time of each value, s (any origin: the logger's clock, time since 1970).
    label : str
        How messages name it (``channel 'Boom_ang'``, ``column 'angle'``...).

    """

    name: str
    t: FloatArray
    values: FloatArray
    label: str


class LogTable(Protocol):
    """A logger's file: channels found by name (or column index), each with its time."""

    source: str

    def channel(self, name: str, role: str) -> Channel:
        """Return the channel ``name``, or raise a one-line :class:`DataError`."""


def check_channel(source: str, channel: Channel) -> Channel:
    """Refuse a channel whose values are not finite or whose time does not increase."""
    if channel.values.size == 0:
        raise DataError(f'{source}: {channel.label}: no values')
    if channel.t.shape != channel.values.shape:
        raise DataError(f'{source}: {channel.label}: {channel.values.size} values for '
                        f'{channel.t.size} times')
    for what, values in (('value', channel.values), ('time', channel.t)):
        bad = np.flatnonzero(~np.isfinite(values))
        if bad.size:
            raise DataError(f'{source}: {channel.label}: {bad.size} {what}s are NaN or infinite '
                            f'(first at sample {bad[0]})')
    fault = first_time_fault(channel.t)
    if fault is not None:
        k = fault.index
        more = f' ({fault.count} times in all)' if fault.count > 1 else ''
        raise DataError(f'{source}: {channel.label}: time {channel.t[k + 1]:.12g} s at sample '
                        f'{k + 1} {fault.kind} {channel.t[k]:.12g} s{more}')
    return channel


@dataclass(frozen=True)
class TimeFault:
    """Where logged times first fail to increase: ``t[index + 1] <= t[index]``."""

    index: int
    kind: str
    count: int


def first_time_fault(t: FloatArray) -> TimeFault | None:
    """
    Find the first time that does not exceed the one before it.

    ``t``: logged times, s.
    Returns: its index ``k`` (``t[k + 1] <= t[k]``), how it fails (``repeats`` or
    ``goes backwards from``) and how many times fail in all; None if ``t`` increases strictly.
    """
    steps = np.diff(t)
    wrong = np.flatnonzero(steps <= 0.0)
    if not wrong.size:
        return None
    k = int(wrong[0])
    return TimeFault(k, 'repeats' if steps[k] == 0.0 else 'goes backwards from', int(wrong.size))


def nanoseconds(t: FloatArray, origin: float) -> IntArray:
    """Return times in integer nanoseconds from ``origin`` (s), differenced before scaling."""
    return np.round((np.asarray(t, dtype=np.float64) - origin) * 1e9).astype(np.int64)


def held_at(samples: IntArray, channel: Channel, origin: float, *, command: bool) -> FloatArray:
    """Return the value of a channel in force at each sample, holding its last value."""
    stamps = nanoseconds(channel.t, origin)
    index = np.searchsorted(stamps, samples, side='left' if command else 'right') - 1
    return channel.values[np.maximum(index, 0)]

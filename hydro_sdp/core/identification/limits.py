"""
The end stops and the valve range an identified model is given, and where each comes from.

The reasoning is in docs/methods.md section 13.2.

"""

from __future__ import annotations

from dataclasses import dataclass
import math
from typing import Literal, Sequence

from hydro_sdp.core.model.records import Record
import numpy as np

#: Where a limit comes from: passed in, seen in the data, or neither.
LimitsSource = Literal['given', 'data', 'none']


@dataclass(frozen=True)
class CommandRange:
    """
    The commands the records used, and where the model's limits come from.

    Parameters
    ----------
    seen : tuple[float, float]
        Smallest and largest command in the records, input units.
    input_limits_from : str
        ``given`` (``input_limits`` passed in) or ``data`` (the range seen).
    angle_limits_from : str
        ``given`` (``angle_limits`` passed in), ``data`` (end stops the joint was
        seen held at) or ``none``.

    """

    seen: tuple[float, float]
    input_limits_from: LimitsSource
    angle_limits_from: LimitsSource


@dataclass(frozen=True)
class ModelLimits:
    """
    The limits written to an identified model.

    Parameters
    ----------
    angle_limits : tuple[float, float] or None
        End stops, degrees (infinite on a side where none was seen).
    input_limits : tuple[float, float]
        Valve range, input units.
    commands : CommandRange
        What the records used and where each limit comes from.

    """

    angle_limits: tuple[float, float] | None
    input_limits: tuple[float, float]
    commands: CommandRange


def commands_seen(records: Sequence[Record]) -> tuple[float, float]:
    """Return the smallest and largest command of the records."""
    return (min(float(np.min(record.v)) for record in records),
            max(float(np.max(record.v)) for record in records))


def model_limits(records: Sequence[Record], end_stops: tuple[float | None, float | None],
                 rest: float, *, angle_limits: tuple[float, float] | None = None,
                 input_limits: tuple[float, float] | None = None) -> ModelLimits:
    """
    Return the limits of an identified model: given, else what the data show.

    ``end_stops``: angles where the joint was seen held against a stop (or the stops given).
    ``angle_limits``: end stops given.
    ``input_limits``: valve range given.
    """
    low, high = commands_seen(records)
    angles: tuple[float, float] | None
    angles_from: LimitsSource
    if angle_limits is not None:
        angles, angles_from = angle_limits, 'given'
    elif end_stops[0] is not None or end_stops[1] is not None:
        # A stop seen on one side stays in the model; the other side has none.
        angles = (-math.inf if end_stops[0] is None else end_stops[0],
                  math.inf if end_stops[1] is None else end_stops[1])
        angles_from = 'data'
    else:
        angles, angles_from = None, 'none'
    if input_limits is not None:
        valve: tuple[float, float] = input_limits
        valve_from: LimitsSource = 'given'
    else:
        valve, valve_from = (min(low, rest), max(high, rest)), 'data'
    return ModelLimits(angles, valve, CommandRange((low, high), valve_from, angles_from))

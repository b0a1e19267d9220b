"""
Telling routine operation from experiments: how much of the driving is done by held levels.

The reasoning is in docs/methods.md section 15.1.

"""

from __future__ import annotations

from typing import Sequence

from hydro_sdp.core.model.records import Record
import numpy as np

#: Records are routine operation when held levels carry less than this share of the
#: samples at which the command is away from rest.
HELD_SHARE = 0.5


def held_share(records: Sequence[Record], rest: float, hold: int) -> float:
    """
    Share of the driven samples that belong to levels held for at least ``hold`` samples.

    ``rest``: rest command (samples at rest are not driven).
    Returns: the share, 0..1 (1 when nothing is driven: there is nothing routine to use).
    """
    driven = held = 0
    for record in records:
        v = record.v
        if v.size == 0:
            continue
        starts = np.flatnonzero(np.r_[True, v[1:] != v[:-1]])
        lengths = np.diff(np.r_[starts, v.size])
        away = v[starts] != rest
        driven += int(np.sum(lengths[away]))
        held += int(np.sum(lengths[away & (lengths >= hold)]))
    return held / driven if driven else 1.0


def routine_operation(records: Sequence[Record], rest: float, hold: int) -> bool:
    """Whether records are routine operation rather than experiments with held levels."""
    return held_share(records, rest, hold) < HELD_SHARE

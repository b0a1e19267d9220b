"""The polynomial gain map of the second paper, per direction (kind ``poly``)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

from hydro_sdp.core.arrays import FloatArray
from hydro_sdp.core.errors import ModelFileError
from hydro_sdp.core.model.static_maps.protocol import MapKind
from hydro_sdp.core.validation import (
    Document, require_float, require_float_list, require_ordered_pair)
import numpy as np


@dataclass(frozen=True)
class PolyMap:
    """
    Polynomial gain map (kind ``poly``), the second paper's ``b(v)`` per direction.

    ``rate(v) = u b(u)`` with ``u = v - rest`` (the command from the valve's rest;
    the paper's ``v`` for rest 0) and ``b(u) = sum_i c_i u^i`` from ``gain_negative``
    for ``u < 0`` and ``gain_positive`` for ``u > 0``; commands are clipped to
    ``command_range``, the range the polynomials were fitted on.

    Parameters
    ----------
    gain_negative : tuple[float, ...]
        Coefficients ``c_0, c_1, ..`` for negative commands, deg/s per input unit.
    gain_positive : tuple[float, ...]
        Coefficients for positive commands.
    command_range : tuple[float, float]
        ``(v_min, v_max)`` with ``v_min < rest < v_max``, input units.
    rest : float
        The command at rest, input units (model-file key ``rest``).

    """

    kind: ClassVar[MapKind] = 'poly'
    keys: ClassVar[tuple[str, ...]] = ('gain_negative', 'gain_positive', 'command_range',
                                       'rest')

    gain_negative: tuple[float, ...]
    gain_positive: tuple[float, ...]
    command_range: tuple[float, float]
    rest: float = 0.0

    def __post_init__(self) -> None:
        for name in ('gain_negative', 'gain_positive'):
            values = tuple(float(x) for x in getattr(self, name))
            if not values or not all(np.isfinite(values)):
                raise ModelFileError(f'key {name!r}: needs finite coefficients')
            object.__setattr__(self, name, values)
        low, high = (float(x) for x in self.command_range)
        rest = float(self.rest)
        if not low < rest < high:
            raise ModelFileError(f"key 'command_range': expected [below rest, above rest] "
                                 f'(rest {rest:g}), got [{low}, {high}]')
        object.__setattr__(self, 'command_range', (low, high))
        object.__setattr__(self, 'rest', rest)

    @property
    def dead_zone(self) -> None:
        """Return None: the polynomial map has no explicit dead-zone."""
        return None

    def rate(self, v: FloatArray) -> FloatArray:
        """Angular velocity (deg/s) for steady commands ``v`` (:meth:`StaticMap.rate`)."""
        u = np.clip(np.asarray(v, dtype=np.float64), *self.command_range) - self.rest
        negative = np.polynomial.polynomial.polyval(u, self.gain_negative)
        positive = np.polynomial.polynomial.polyval(u, self.gain_positive)
        # A valve's gain is never negative: where the polynomials, fitted on the commands
        # the runs held, cross zero between them (outside the data), the joint is still.
        return u * np.maximum(np.where(u < 0.0, negative, positive), 0.0)

    def to_mapping(self) -> dict[str, float | list[float]]:
        """Return the model-file keys of this map."""
        return {'gain_negative': list(self.gain_negative),
                'gain_positive': list(self.gain_positive),
                'command_range': list(self.command_range), 'rest': self.rest}

    @classmethod
    def from_mapping(cls, data: Document) -> PolyMap:
        """Build the map from model-file keys (already checked for presence)."""
        return cls(gain_negative=require_float_list(data['gain_negative'], 'gain_negative'),
                   gain_positive=require_float_list(data['gain_positive'], 'gain_positive'),
                   command_range=require_ordered_pair(data['command_range'], 'command_range'),
                   rest=require_float(data['rest'], 'rest'))

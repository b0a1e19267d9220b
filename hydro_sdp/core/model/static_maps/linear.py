"""The linear integrator gain, eq. (2) of West et al. (2018) with a1 = -1 (kind ``linear``)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

from hydro_sdp.core.arrays import FloatArray
from hydro_sdp.core.errors import ModelFileError
from hydro_sdp.core.model.static_maps.protocol import MapKind
from hydro_sdp.core.validation import Document, require_float
import numpy as np


@dataclass(frozen=True)
class LinearMap:
    """
    Linear integrator gain (kind ``linear``, eq. (2) of West et al. with a1 = -1).

    Parameters
    ----------
    gain : float
        deg/s per input unit.

    """

    kind: ClassVar[MapKind] = 'linear'
    keys: ClassVar[tuple[str, ...]] = ('gain',)

    gain: float

    def __post_init__(self) -> None:
        if not self.gain > 0.0:
            raise ModelFileError(f"key 'gain': must be > 0, got {self.gain}")

    @property
    def dead_zone(self) -> None:
        """Return None: a linear map has no dead-zone."""
        return None

    def rate(self, v: FloatArray) -> FloatArray:
        """Angular velocity (deg/s) for steady commands ``v`` (:meth:`StaticMap.rate`)."""
        return self.gain * np.asarray(v, dtype=np.float64)

    def to_mapping(self) -> dict[str, float | list[float]]:
        """Return the model-file keys of this map."""
        return {'gain': self.gain}

    @classmethod
    def from_mapping(cls, data: Document) -> LinearMap:
        """Build the map from model-file keys (already checked for presence)."""
        return cls(gain=require_float(data['gain'], 'gain'))

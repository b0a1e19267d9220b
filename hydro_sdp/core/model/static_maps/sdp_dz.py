"""The piecewise-linear dead-zone map, eq. (6) of West et al. (2018) (kind ``sdp_dz``)."""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import ClassVar

from hydro_sdp.core.arrays import FloatArray
from hydro_sdp.core.model.static_maps.protocol import check_dead_zone, check_positive_pair, MapKind
from hydro_sdp.core.validation import Document, require_ordered_pair, require_pair
import numpy as np


@dataclass(frozen=True)
class SdpDzMap:
    """
    Piecewise-linear dead-zone map (kind ``sdp_dz``, eq. (6) of West et al.).

    Parameters
    ----------
    dead_zone : tuple[float, float]
        Edges ``(a3, a6)`` in input units.
    slope : tuple[float, float]
        ``(s_n, s_p)``, deg/s per input unit beyond each edge.

    """

    kind: ClassVar[MapKind] = 'sdp_dz'
    keys: ClassVar[tuple[str, ...]] = ('dead_zone', 'slope')

    dead_zone: tuple[float, float]
    slope: tuple[float, float]

    def __post_init__(self) -> None:
        check_dead_zone(self.dead_zone)
        check_positive_pair('slope', self.slope)

    def rate(self, v: FloatArray) -> FloatArray:
        """Angular velocity (deg/s) for steady commands ``v`` (:meth:`StaticMap.rate`)."""
        v = np.asarray(v, dtype=np.float64)
        low, high = self.dead_zone
        return self.slope[0] * np.minimum(v - low, 0.0) + self.slope[1] * np.maximum(v - high, 0.0)

    def shifted(self, shift: tuple[float, float]) -> SdpDzMap:
        """Return the map with ``shift`` added to its lower and upper edge, input units."""
        return replace(self, dead_zone=(self.dead_zone[0] + shift[0],
                                        self.dead_zone[1] + shift[1]))

    def to_mapping(self) -> dict[str, float | list[float]]:
        """Return the model-file keys of this map."""
        return {'dead_zone': list(self.dead_zone), 'slope': list(self.slope)}

    @classmethod
    def from_mapping(cls, data: Document) -> SdpDzMap:
        """Build the map from model-file keys (already checked for presence)."""
        return cls(dead_zone=require_ordered_pair(data['dead_zone'], 'dead_zone', strict=False),
                   slope=require_pair(data['slope'], 'slope'))

"""The map families by kind name (:data:`MAP_KINDS`), and what applies to any map."""

from __future__ import annotations

from hydro_sdp.core.errors import ConfigurationError
from hydro_sdp.core.model.static_maps.linear import LinearMap
from hydro_sdp.core.model.static_maps.poly import PolyMap
from hydro_sdp.core.model.static_maps.power_sat import PowerSatMap
from hydro_sdp.core.model.static_maps.protocol import ShiftableMap, StaticMap
from hydro_sdp.core.model.static_maps.pwl import PwlMap
from hydro_sdp.core.model.static_maps.sdp import SdpMap
from hydro_sdp.core.model.static_maps.sdp_dz import SdpDzMap

#: Map classes by the model file's ``kind``.
MAP_KINDS: dict[str, type[StaticMap]] = {
    cls.kind: cls for cls in (SdpMap, SdpDzMap, LinearMap, PwlMap, PolyMap, PowerSatMap)
}


def shifted_map(static_map: StaticMap, shift: tuple[float, float]) -> StaticMap:
    """Return ``static_map`` with its dead-zone edges moved by ``shift`` (input units)."""
    if shift == (0.0, 0.0):
        return static_map
    if not isinstance(static_map, ShiftableMap):
        raise ConfigurationError(f'dead_zone_shift needs an sdp or sdp_dz model, not '
                                 f'{static_map.kind}')
    return static_map.shifted(shift)

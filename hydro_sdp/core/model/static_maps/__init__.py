"""
Static maps from the valve command to the joint's angular velocity.

A hydraulic joint is an integrator whose speed is a static function of the
delayed command: ``y_k = y_{k-1} + dt * rate(v_{k-tau})``. Each family of that
function (one ``kind`` of the model file) is one class in its own module
satisfying :class:`StaticMap`, with its parameters in rate units (deg/s) so that
the same map serves every sample period; :data:`MAP_KINDS` registers them.

"""

from hydro_sdp.core.model.static_maps.linear import LinearMap
from hydro_sdp.core.model.static_maps.poly import PolyMap
from hydro_sdp.core.model.static_maps.power_sat import power_sat_rate, PowerSatMap
from hydro_sdp.core.model.static_maps.protocol import MapKind, ShiftableMap, StaticMap
from hydro_sdp.core.model.static_maps.pwl import PwlMap
from hydro_sdp.core.model.static_maps.registry import MAP_KINDS, shifted_map
from hydro_sdp.core.model.static_maps.sdp import (
    chord_commands, CHORD_SPEED_FRACTION, linearise, sdp_rate, SdpMap)
from hydro_sdp.core.model.static_maps.sdp_dz import SdpDzMap

__all__ = [
    'CHORD_SPEED_FRACTION', 'LinearMap', 'MAP_KINDS', 'MapKind', 'PolyMap', 'PowerSatMap',
    'PwlMap', 'SdpDzMap', 'SdpMap', 'ShiftableMap', 'StaticMap', 'chord_commands', 'linearise',
    'power_sat_rate', 'sdp_rate', 'shifted_map',
]

"""The commands a map's IDZ table covers: the valve's range, else the map's own (methods 5.4)."""

from __future__ import annotations

import math

from hydro_sdp.core.errors import ConfigurationError
from hydro_sdp.core.model.joint_model import JointModel
from hydro_sdp.core.model.static_maps import PolyMap, PowerSatMap, PwlMap, SdpMap

#: Fraction of saturation where a table of a saturating map without input limits ends.
TABLE_SATURATION = 0.99


def command_span(model: JointModel,
                 v_range: tuple[float, float] | None = None) -> tuple[float, float]:
    """
    Return the commands an IDZ table (or the chords of ``chord_map``) covers, input units.

    ``v_range``: commands to cover.
    Returns: ``(low, high)`` with the rest command strictly between.
    """
    static_map = model.static_map
    if v_range is not None:
        span = (float(v_range[0]), float(v_range[1]))
    elif model.input_limits is not None:
        span = model.input_limits
    elif isinstance(static_map, PwlMap):
        span = (static_map.knots[0], static_map.knots[-1])
    elif isinstance(static_map, PolyMap):
        span = static_map.command_range
    elif isinstance(static_map, (SdpMap, PowerSatMap)):
        reach = -math.log(1.0 - TABLE_SATURATION)
        power = static_map.exponent if isinstance(static_map, PowerSatMap) else (1.0, 1.0)
        low, high = static_map.dead_zone
        span = (low - reach ** (1.0 / power[0]) / static_map.curvature[0],
                high + reach ** (1.0 / power[1]) / static_map.curvature[1])
    else:
        raise ConfigurationError(f'an IDZ table of a {model.kind} map needs the command range: '
                                 'give the model input_limits (or --v-range)')
    rest = model.rest_command
    if not (math.isfinite(span[0]) and math.isfinite(span[1]) and span[0] < rest < span[1]):
        raise ConfigurationError(f'the command range {list(span)} must contain the rest '
                                 f'command {rest} strictly inside')
    return span

"""The ``idz`` mapping of a controller file, in either form (docs/interfaces.md section 6)."""

from __future__ import annotations

from typing import Mapping

from hydro_sdp.core.control.idz import IDZ_MODES, InverseDeadZone
from hydro_sdp.core.control.idz_table import Idz, TableInverseDeadZone
from hydro_sdp.core.errors import ConfigurationError, ModelFileError
from hydro_sdp.core.validation import (
    require_float, require_float_list, require_ordered_pair, require_pair)

_CHORD_KEYS = {'mode', 'beta', 'dead_zone', 'slopes', 'rest', 'fade'}
_TABLE_KEYS = {'mode', 'beta', 'table', 'rest', 'fade'}


def idz_to_mapping(idz: Idz | None) -> dict[str, object] | None:
    """Return the ``idz`` value of a controller file (``None`` for no IDZ)."""
    if idz is None:
        return None
    faded: dict[str, object] = {'fade': idz.fade} if idz.fade > 0.0 else {}
    if isinstance(idz, TableInverseDeadZone):
        return {'mode': idz.mode, 'beta': idz.beta, **faded, 'rest': idz.rest,
                'table': {'u': list(idz.u), 'v': list(idz.v)}}
    return {'mode': idz.mode, 'beta': idz.beta, **faded, 'dead_zone': list(idz.dead_zone),
            'slopes': list(idz.slopes), 'rest': idz.rest}


def idz_from_mapping(data: object) -> Idz | None:
    """
    Validate a controller file's ``idz`` value and build the IDZ.

    ``data``: the parsed value: null, a chord mapping or a table mapping.
    Raises ModelFileError naming the key when anything is missing, unknown or invalid.
    """
    if data is None:
        return None
    if not isinstance(data, Mapping):
        raise ModelFileError("key 'idz': expected a mapping or null")
    table = 'table' in data
    unknown = sorted(set(data) - (_TABLE_KEYS if table else _CHORD_KEYS), key=str)
    if unknown:
        extra = ' (a table IDZ has no dead_zone or slopes: they follow from the table)' \
            if table and set(unknown) & {'dead_zone', 'slopes'} else ''
        raise ModelFileError(f"key 'idz': unknown key {unknown[0]!r}{extra}")
    mode = data.get('mode', 'zero')
    if mode not in IDZ_MODES:
        raise ModelFileError(f"key 'idz.mode': expected one of {', '.join(IDZ_MODES)}, "
                             f'got {mode!r}')
    beta = require_float(data.get('beta', 0.05), 'idz.beta')
    rest = require_float(data.get('rest', 0.0), 'idz.rest')
    fade = require_float(data.get('fade', 0.0), 'idz.fade')
    try:
        if table:
            points = data['table']
            if not isinstance(points, Mapping) or set(points) != {'u', 'v'}:
                raise ModelFileError("key 'idz.table': expected a mapping with keys 'u' and 'v'")
            return TableInverseDeadZone(u=require_float_list(points['u'], 'idz.table.u'),
                                        v=require_float_list(points['v'], 'idz.table.v'),
                                        beta=beta, mode=mode, rest=rest, fade=fade)
        for key in ('dead_zone', 'slopes'):
            if key not in data:
                raise ModelFileError(f"key 'idz': missing key {key!r}")
        return InverseDeadZone(
            dead_zone=require_ordered_pair(data['dead_zone'], 'idz.dead_zone', strict=False),
            slopes=require_pair(data['slopes'], 'idz.slopes'), beta=beta, mode=mode, rest=rest,
            fade=fade)
    except ConfigurationError as error:
        raise ModelFileError(f"key 'idz': {error}") from None

"""
Small checks shared by the file and configuration readers and by settings objects.

File helpers raise :class:`ModelFileError` naming the key; the settings helper raises
:class:`ConfigurationError` naming the field.
"""

from __future__ import annotations

from collections.abc import Collection, Mapping
import math

from hydro_sdp.core.errors import ConfigurationError, ModelFileError

#: A mapping read from a YAML or JSON file: string keys, values not yet checked.
Document = Mapping[str, object]


def require_float(value: object, key: str) -> float:
    """Return ``value`` as a finite float, or raise naming the dotted ``key``."""
    # YAML reads 'true' as bool, which Python would happily treat as 1.
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ModelFileError(f'key {key!r}: expected a number, got {_describe(value)}')
    number = float(value)
    if not math.isfinite(number):
        raise ModelFileError(f'key {key!r}: must be finite, got {number}')
    return number


def require_pair(value: object, key: str) -> tuple[float, float]:
    """Return ``value`` as a pair of finite floats, or raise naming ``key``."""
    if not isinstance(value, (list, tuple)) or len(value) != 2:
        raise ModelFileError(
            f'key {key!r}: expected a list of two numbers, got {_describe(value)}')
    return (require_float(value[0], f'{key}[0]'), require_float(value[1], f'{key}[1]'))


def require_ordered_pair(value: object, key: str, *, strict: bool = True) -> tuple[float, float]:
    """Return a pair whose first element is below the second (or equal, unless ``strict``)."""
    low, high = require_pair(value, key)
    if low > high or (strict and low == high):
        relation = '<' if strict else '<='
        raise ModelFileError(
            f'key {key!r}: the first value must be {relation} the second, got [{low}, {high}]')
    return low, high


def require_float_list(value: object, key: str) -> tuple[float, ...]:
    """Return ``value`` as a tuple of finite floats, or raise naming ``key``."""
    if not isinstance(value, (list, tuple)):
        raise ModelFileError(f'key {key!r}: expected a list of numbers')
    return tuple(require_float(item, f'{key}[{i}]') for i, item in enumerate(value))


def read_document(data: object, what: str, file_format: str, known: Collection[str],
                  required: Collection[str] = ()) -> Document:
    """Return a parsed file as a mapping with known keys, the required ones, the right format."""
    if not isinstance(data, Mapping):
        raise ModelFileError(f'{what} must be a mapping of keys, got {type(data).__name__}')
    _check_keys(data, known, required)
    found = data.get('format')
    if found != file_format:
        raise ModelFileError(f"key 'format': expected {file_format!r}, got {found!r}")
    return data


def require_mapping(value: object, where: str, known: Collection[str],
                    required: Collection[str] = (), *,
                    expected: str = 'a mapping of keys') -> Document:
    """Return a nested ``value`` as a mapping with known keys and the required ones."""
    if not isinstance(value, Mapping):
        raise ModelFileError(f'key {where!r}: expected {expected}')
    _check_keys(value, known, required, where)
    return value


def _check_keys(data: Collection[object], known: Collection[str], required: Collection[str],
                where: str = '') -> None:
    """Refuse a key not in ``known``, then a missing ``required`` one; ``where`` names ``data``."""
    for key in data:
        if not isinstance(key, str) or key not in known:
            raise ModelFileError(f'unknown key {_key_name(key, where)}')
    for key in required:
        if key not in data:
            raise ModelFileError(f'missing required key {_key_name(key, where)}')


def _key_name(key: object, where: str) -> str:
    # Top-level keys are quoted, nested ones are written as a dotted path.
    return f'{where}.{key}' if where else repr(key)


def require_positive_fields(settings: object, names: Collection[str], *,
                            zero_allowed: bool = False) -> None:
    """Refuse a field of ``settings`` that is not a finite number above 0 (or at least 0)."""
    for name in names:
        value = getattr(settings, name)
        if not (math.isfinite(value) and (value >= 0.0 if zero_allowed else value > 0.0)):
            rule = 'a number >= 0' if zero_allowed else 'a positive number'
            raise ConfigurationError(f'{name} must be {rule}, got {value}')


def _describe(value: object) -> str:
    text = repr(value)
    if len(text) > 40:
        text = text[:37] + '...'
    return f'{type(value).__name__} {text}'

"""
Small checks shared by the model-file and configuration readers.

Each helper raises :class:`ModelFileError` whose message names the key and the
reason, so that a user can fix the file from the message alone.

"""

from __future__ import annotations

import math
from typing import Any

from hydro_sdp.core.errors import ModelFileError


def require_float(value: Any, key: str) -> float:
    """
    Return ``value`` as a finite float, or raise naming ``key``.

    Parameters
    ----------
    value : Any
        Value read from the file.
    key : str
        Dotted key name used in the error message.

    Returns
    -------
    float
        The value as a float.

    """
    # YAML reads 'true' as bool, which Python would happily treat as 1.
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ModelFileError(f'key {key!r}: expected a number, got {_describe(value)}')
    number = float(value)
    if not math.isfinite(number):
        raise ModelFileError(f'key {key!r}: must be finite, got {number}')
    return number


def require_pair(value: Any, key: str) -> tuple[float, float]:
    """
    Return ``value`` as a pair of finite floats, or raise naming ``key``.

    Parameters
    ----------
    value : Any
        Value read from the file; a two-element list.
    key : str
        Key name used in the error message.

    Returns
    -------
    tuple[float, float]
        The two numbers.

    """
    if not isinstance(value, (list, tuple)) or len(value) != 2:
        raise ModelFileError(
            f'key {key!r}: expected a list of two numbers, got {_describe(value)}')
    return (require_float(value[0], f'{key}[0]'), require_float(value[1], f'{key}[1]'))


def require_ordered_pair(value: Any, key: str, *, strict: bool = True) -> tuple[float, float]:
    """
    Return a pair whose first element is below (or at most, if not strict) the second.

    Parameters
    ----------
    value : Any
        Value read from the file.
    key : str
        Key name used in the error message.
    strict : bool
        Whether equal elements are refused.

    Returns
    -------
    tuple[float, float]
        The ordered pair.

    """
    low, high = require_pair(value, key)
    if low > high or (strict and low == high):
        relation = '<' if strict else '<='
        raise ModelFileError(
            f'key {key!r}: the first value must be {relation} the second, got [{low}, {high}]')
    return low, high


def require_float_list(value: Any, key: str) -> tuple[float, ...]:
    """
    Return ``value`` as a tuple of finite floats, or raise naming ``key``.

    Parameters
    ----------
    value : Any
        Value read from the file; a list of numbers.
    key : str
        Key name used in the error message.

    Returns
    -------
    tuple[float, ...]
        The numbers.

    """
    if not isinstance(value, (list, tuple)):
        raise ModelFileError(f'key {key!r}: expected a list of numbers')
    return tuple(require_float(item, f'{key}[{i}]') for i, item in enumerate(value))


def _describe(value: Any) -> str:
    text = repr(value)
    if len(text) > 40:
        text = text[:37] + '...'
    return f'{type(value).__name__} {text}'

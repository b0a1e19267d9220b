"""A set request of parameters, read by name with the type each use needs."""

from __future__ import annotations

from typing import Iterable, Sequence

from hydro_sdp.core.errors import ConfigurationError
from hydro_sdp.ros.parameters.spec import shown
from rclpy.parameter import Parameter


def array_items(value: object) -> list[float | str]:
    """Return an array parameter's items (a list, or an ``array.array`` from a message)."""
    assert isinstance(value, Iterable)
    return list(value)


class ParameterRequest:
    """The values of a set request, by name."""

    def __init__(self, parameters: Sequence[Parameter]) -> None:
        self._values: dict[str, object] = {p.name: p.value for p in parameters}

    @property
    def names(self) -> frozenset[str]:
        """Return the names the request sets."""
        return frozenset(self._values)

    def __contains__(self, name: object) -> bool:
        """Return whether the request sets ``name``."""
        return name in self._values

    def get(self, name: str, current: object) -> object:
        """Return the value the request gives ``name``, or ``current``."""
        return self._values.get(name, current)

    def number(self, name: str, current: float) -> float:
        """Return the number the request gives ``name``, or ``current``."""
        value = self._values.get(name, current)
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ConfigurationError(f'parameter {name!r} needs a number, got {shown(value)}')
        return float(value)

    def numbers(self, name: str, current: Sequence[float]) -> tuple[float, ...]:
        """Return the numbers the request gives ``name`` (an unset array: none), or ``current``."""
        value = self._values.get(name, current)
        if value is None:
            return ()
        if isinstance(value, (str, bytes)) or not isinstance(value, Iterable):
            raise ConfigurationError(f'parameter {name!r} needs numbers, got {shown(value)}')
        return tuple(float(x) for x in value)

    def pair(self, name: str, current: tuple[float, float]) -> tuple[float, float]:
        """Return the two numbers the request gives ``name``, or ``current``."""
        values = self.numbers(name, current)
        if len(values) != 2:
            raise ConfigurationError(f'parameter {name!r} needs two numbers, '
                                     f'got {shown(list(values))}')
        return values[0], values[1]

    def text(self, name: str, current: str) -> str:
        """Return the string the request gives ``name``, or ``current``."""
        return str(self._values.get(name, current))

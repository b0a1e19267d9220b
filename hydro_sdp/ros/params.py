"""Declaring ROS parameters with descriptions and ranges in one line each."""

from __future__ import annotations

from typing import Any

from hydro_sdp.core.errors import ConfigurationError
from rcl_interfaces.msg import FloatingPointRange, IntegerRange, ParameterDescriptor
from rclpy.node import Node
from rclpy.parameter import Parameter


def declare(node: Node, name: str, default: Any, description: str, *,
            low: float | None = None, high: float | None = None,
            read_only: bool = False) -> Any:
    """
    Declare one parameter and return its value (an override from the command line wins).

    Parameters
    ----------
    node : Node
        The node.
    name : str
        Parameter name (dots group it in YAML).
    default : Any
        Default value, or a ``Parameter.Type`` for a typed parameter with no default.
    description : str
        What it is, with its unit.
    low, high : float or None
        Range, enforced by rclpy on declaration and on every set.
    read_only : bool
        Whether it can change at run time.

    Returns
    -------
    Any
        The value (None for a typed parameter that nobody set).

    """
    descriptor = ParameterDescriptor(description=description, read_only=read_only)
    if low is not None and high is not None:
        if isinstance(default, int) and not isinstance(default, bool):
            descriptor.integer_range = [IntegerRange(from_value=int(low), to_value=int(high),
                                                     step=0)]
        else:
            descriptor.floating_point_range = [FloatingPointRange(from_value=float(low),
                                                                  to_value=float(high),
                                                                  step=0.0)]
    return node.declare_parameter(name, default, descriptor).value


def pair(value: Any, name: str) -> tuple[float, float]:
    """Return a two-element parameter as a tuple, or raise naming it."""
    if value is None or len(value) != 2:
        raise ConfigurationError(f'parameter {name!r} needs two numbers, got {value!r}')
    return float(value[0]), float(value[1])


def value_of(parameters: list[Parameter], name: str, current: Any) -> Any:
    """Return the new value of ``name`` in a set request, or ``current``."""
    for parameter in parameters:
        if parameter.name == name:
            return parameter.value
    return current

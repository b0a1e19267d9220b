"""
Declaring ROS parameters with descriptions and ranges in one line each.

:func:`declare` also makes a double parameter take an integer, as users of
``ros2 param set NODE gains.k_i 1`` or ``-p feedback_timeout:=1`` expect (rclpy
alone refuses it as the wrong type): an override given at start-up is converted
before the declaration, and a value set at run time by a pre-set callback
(:func:`integers_as_doubles`), so the declared range still applies.

"""

from __future__ import annotations

from typing import Any

from hydro_sdp.core.errors import ConfigurationError
from rcl_interfaces.msg import FloatingPointRange, IntegerRange, ParameterDescriptor
from rclpy.node import Node
from rclpy.parameter import Parameter

_WIDENED = {Parameter.Type.INTEGER: Parameter.Type.DOUBLE,
            Parameter.Type.INTEGER_ARRAY: Parameter.Type.DOUBLE_ARRAY}
# Marks a node whose pre-set callback is registered (rclpy concatenates the lists that
# several pre-set callbacks return, so there must be exactly one).
_HOOKED = '_hydro_sdp_integers_as_doubles'
# Twin parameter names of a node (name -> twin), kept in step by the pre-set callback.
_ALIASES = '_hydro_sdp_parameter_aliases'


def as_double(parameter: Parameter, declared: Parameter.Type) -> Parameter:
    """
    Return ``parameter`` as a double (array) if it is an integer (array) and ``declared`` is.

    Parameters
    ----------
    parameter : Parameter
        A value being set.
    declared : Parameter.Type
        The declared type of the parameter.

    Returns
    -------
    Parameter
        The converted parameter, or ``parameter`` itself.

    """
    if _WIDENED.get(parameter.type_) != declared:
        return parameter
    value = parameter.value
    converted = [float(x) for x in value] if declared == Parameter.Type.DOUBLE_ARRAY \
        else float(value)
    return Parameter(parameter.name, declared, converted)


def integers_as_doubles(node: Node, parameters: list[Parameter]) -> list[Parameter]:
    """
    Pre-set callback: convert integer values of declared double parameters, add twins.

    Parameters
    ----------
    node : Node
        The node whose parameters are set.
    parameters : list of Parameter
        The request.

    Returns
    -------
    list of Parameter
        The request with integers of double parameters as doubles, and the twin
        (:func:`alias`) of every name it sets whose twin it does not set.

    """
    converted = [as_double(p, Parameter.Type(node.describe_parameter(p.name).type))
                 if node.has_parameter(p.name) else p for p in parameters]
    aliases: dict[str, str] = getattr(node, _ALIASES, {})
    if not aliases:
        return converted
    # A value set under one of two twin names is set under the other too, in the same request.
    named = {p.name for p in converted}
    twins = [Parameter(aliases[p.name], p.type_, p.value) for p in converted
             if p.name in aliases and aliases[p.name] not in named]
    return converted + twins


def alias(node: Node, name: str, twin: str) -> None:
    """
    Make two declared parameters one: a set request naming either sets both.

    Parameters
    ----------
    node : Node
        The node (its pre-set callback is :func:`integers_as_doubles`, see :func:`declare`).
    name, twin : str
        The two names.

    """
    aliases = getattr(node, _ALIASES, None)
    if aliases is None:
        aliases = {}
        setattr(node, _ALIASES, aliases)
    aliases[name], aliases[twin] = twin, name


def unalias(node: Node, names: list[str]) -> None:
    """Forget the twins of ``names`` (before undeclaring them)."""
    aliases = getattr(node, _ALIASES, {})
    for name in names:
        twin = aliases.pop(name, None)
        if twin is not None:
            aliases.pop(twin, None)


def _declared_type(default: Any) -> Parameter.Type | None:
    if isinstance(default, Parameter.Type):
        return default
    if isinstance(default, float):
        return Parameter.Type.DOUBLE
    if isinstance(default, list) and default and all(isinstance(x, float) for x in default):
        return Parameter.Type.DOUBLE_ARRAY
    return None


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
    if not getattr(node, _HOOKED, False):
        node.add_pre_set_parameters_callback(lambda ps: integers_as_doubles(node, ps))
        setattr(node, _HOOKED, True)
    declared = _declared_type(default)
    # rclpy keeps start-up overrides (-p, params files) only in this attribute, and checks
    # their type against the default's before any callback could convert them.
    overrides = node._parameter_overrides
    if declared is not None and name in overrides:
        overrides[name] = as_double(overrides[name], declared)
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

"""Parameter descriptors from a table's rows, and integers taken for doubles."""

from __future__ import annotations

from hydro_sdp.ros.parameters.spec import ParameterSpec
from rcl_interfaces.msg import FloatingPointRange, IntegerRange, ParameterDescriptor
from rclpy.parameter import Parameter

#: rclpy's type of each table type.
ROS_TYPES = {'bool': Parameter.Type.BOOL, 'int': Parameter.Type.INTEGER,
             'double': Parameter.Type.DOUBLE, 'string': Parameter.Type.STRING,
             'double_array': Parameter.Type.DOUBLE_ARRAY,
             'string_array': Parameter.Type.STRING_ARRAY}
_WIDENED = {Parameter.Type.INTEGER: Parameter.Type.DOUBLE,
            Parameter.Type.INTEGER_ARRAY: Parameter.Type.DOUBLE_ARRAY}


def as_double(parameter: Parameter, declared: Parameter.Type) -> Parameter:
    """Return ``parameter`` as a double (array) if it is an integer (array) and ``declared`` is."""
    if _WIDENED.get(parameter.type_) != declared:
        return parameter
    value = parameter.value
    converted = [float(x) for x in value] if declared == Parameter.Type.DOUBLE_ARRAY \
        else float(value)
    return Parameter(parameter.name, declared, converted)


def descriptor(spec: ParameterSpec, description: str | None = None) -> ParameterDescriptor:
    """
    Return the descriptor of a parameter: description, read-only, range, constraints.

    ``spec``: the table's row.
    ``description``: the text to show instead of the table's (a joint's name in front).
    """
    result = ParameterDescriptor(description=description or spec.documented,
                                 read_only=spec.read_only, type=ROS_TYPES[spec.kind].value)
    if spec.low is not None and spec.high is not None:
        if spec.kind == 'int':
            result.integer_range = [IntegerRange(from_value=int(spec.low),
                                                 to_value=int(spec.high), step=0)]
        else:
            result.floating_point_range = [FloatingPointRange(
                from_value=float(spec.low), to_value=float(spec.high), step=0.0)]
    constraints = []
    if spec.length is not None:
        constraints.append(f'exactly {spec.length} values')
    if spec.choices:
        constraints.append(f"one of: {', '.join(spec.choices)}")
    if spec.required:
        constraints.append('required')
    result.additional_constraints = '; '.join(constraints)
    return result

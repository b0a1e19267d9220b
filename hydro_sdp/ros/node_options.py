"""The keyword options of rclpy's ``Node``, as the nodes take them and pass them on."""

from __future__ import annotations

from typing import TypedDict

from rclpy.context import Context
from rclpy.parameter import Parameter


class NodeOptions(TypedDict, total=False):
    """Keyword options of :class:`rclpy.node.Node`, all optional, passed on unchanged."""

    context: Context | None
    cli_args: list[str] | None
    namespace: str | None
    use_global_arguments: bool
    enable_rosout: bool
    start_parameter_services: bool
    parameter_overrides: list[Parameter] | None
    allow_undeclared_parameters: bool
    automatically_declare_parameters_from_overrides: bool
    enable_logger_service: bool

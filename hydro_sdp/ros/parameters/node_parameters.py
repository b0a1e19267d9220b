"""A node's parameters declared from its table, checked whole and applied whole."""

from __future__ import annotations

from functools import partial
from typing import Callable, cast, Iterable, Mapping, Union

from hydro_sdp.core.errors import ConfigurationError, HydroSdpError
from hydro_sdp.core.model.timing import SamplePeriod
from hydro_sdp.ros.parameters.descriptors import as_double, descriptor, ROS_TYPES
from hydro_sdp.ros.parameters.request import array_items, ParameterRequest
from hydro_sdp.ros.parameters.spec import (
    MAX_CHARACTERS, MAX_NAMES, ParameterSpec, ParameterTable, ParameterValue, size_error)
from rcl_interfaces.msg import SetParametersResult
from rcl_interfaces.srv import (
    DescribeParameters, GetParameters, GetParameterTypes, ListParameters, SetParameters,
    SetParametersAtomically)
from rclpy.node import Node
from rclpy.parameter import Parameter

__all__ = ['NodeParameters', 'ParameterRequest']

#: A set request of the parameter services, and its answer.
Request = Union[SetParameters.Request, SetParametersAtomically.Request]
Response = Union[SetParameters.Response, SetParametersAtomically.Response]
#: A request of the reading services, and its answer.
Queried = Union[GetParameters.Request, DescribeParameters.Request, GetParameterTypes.Request,
                ListParameters.Request]
Answered = Union[GetParameters.Response, DescribeParameters.Response,
                 GetParameterTypes.Response, ListParameters.Response]


class NodeParameters:
    """
    The parameters of one node: declared from its table, checked and applied whole.

    ``node``: the node (its parameter callbacks are registered here; register no others).
    ``table``: the node's table.
    ``check``: the node's own check of a request, after the table's: raises
    :class:`~hydro_sdp.core.errors.HydroSdpError` (or ``ValueError``) to refuse it.
    ``apply``: for every writable parameter declared once per node, what makes a new value take
    effect (called with no argument, once per accepted request however many of its names share it,
    after the values are set; it reads them back).
    ``apply_joint``: what makes a request of per-joint parameters take effect (required when the
    table has writable per-joint parameters); called with the request.
    Raises ValueError if a writable parameter has no handler: it would take no effect.
    """

    def __init__(self, node: Node, table: ParameterTable, *,
                 check: Callable[[ParameterRequest], None] | None = None,
                 apply: Mapping[str, Callable[[], None]] | None = None,
                 apply_joint: Callable[[ParameterRequest], None] | None = None) -> None:
        self._node = node
        self.table = table
        self._check = check
        self._apply = dict(apply or {})
        self._apply_joint = apply_joint
        writable = {spec.name for spec in table.node_specs if not spec.read_only}
        if writable != set(self._apply):
            raise ValueError(f'{table.node_name}: writable parameters and their handlers '
                             f'differ: {sorted(writable ^ set(self._apply))}')
        if apply_joint is None and any(not s.read_only for s in table.joint_specs):
            raise ValueError(f'{table.node_name}: per-joint parameters need apply_joint')
        # Name -> twin: the plain and the per-joint name of a one-joint node's parameter.
        self._twins: dict[str, str] = {}
        # Until start(): declarations, checked against the table only.
        self._started = False
        # Why the pre-set callback refused the request being set ('' for none).
        self._oversized = ''
        node.add_pre_set_parameters_callback(self._before_set)
        node.add_on_set_parameters_callback(self._on_set)
        node.add_post_set_parameters_callback(self._after_set)
        for service in node.services:
            if service.srv_type in (SetParameters, SetParametersAtomically):
                service.callback = partial(self._sized, service.callback)
            elif service.srv_type in (GetParameters, DescribeParameters, GetParameterTypes,
                                      ListParameters):
                service.callback = partial(self._listed, service.callback)

    # Declaration.
    def declare(self, names: Iterable[str] | None = None,
                defaults: Mapping[str, ParameterValue] | None = None) -> None:
        """
        Declare per-node parameters (an override from the command line or a file wins).

        ``names``: the parameters to declare (default: every per-node one of the table not yet
        declared, but those declared on demand).
        ``defaults``: defaults the node computes, by name (required for those the table has none
        for).
        Raises rclpy.exceptions.ParameterException if a value given at start-up breaks the table
        (wrong type, range, length...).
        Raises ConfigurationError if a required parameter is not given.
        """
        wanted = [spec for spec in self.table.node_specs
                  if not spec.on_demand and not self.declared(spec.name)] \
            if names is None else [self.table[name] for name in names]
        computed = dict(defaults or {})
        for spec in wanted:
            default = computed.get(spec.name, spec.default)
            self._declare(spec.name, spec, default)
            spec.require(self.value(spec.name))

    def declare_joint(self, joint: str, values: Mapping[str, ParameterValue | None],
                      single: bool) -> list[str]:
        """
        Declare a joint's parameters as ``<joint>.<name>``, and the plain names for one joint.

        ``values``: default of each per-joint parameter the joint has, by plain name (None: unset).
        ``single``: whether the node has this joint only: the plain names are declared too, and
        kept in step with the joint's.
        Returns: the joint's names (``<joint>.<name>``), in the order of ``values``.
        """
        declared = []
        started, self._started = self._started, False     # checked against the table only
        try:
            for name, default in values.items():
                declared.append(self._declare_twins(joint, name, default, single))
        finally:
            self._started = started
        return declared

    def _declare_twins(self, joint: str, name: str, default: ParameterValue | None,
                       single: bool) -> str:
        spec = self.table[name]
        prefixed = f'{joint}.{name}'
        value = default
        if single:
            # The plain name of a one-joint node: an override of it becomes the default of
            # the joint's own name, and from then on the two are one.
            declared = self._declare(name, spec, default)
            if declared is not None:
                value = cast(ParameterValue, declared)
        self._declare(prefixed, spec, value, f'{joint}: {spec.documented}')
        if single:
            self._twins[name], self._twins[prefixed] = prefixed, name
        return prefixed

    def undeclare_joint(self, joint: str, names: Iterable[str], single: bool) -> None:
        """Undeclare a joint's parameters (given by plain name), and their plain twins."""
        node = self._node
        for name in names:
            for declared in ([f'{joint}.{name}', name] if single else [f'{joint}.{name}']):
                self._twins.pop(declared, None)
                if node.has_parameter(declared):
                    node.undeclare_parameter(declared)

    def _declare(self, name: str, spec: ParameterSpec, default: ParameterValue | None,
                 description: str | None = None) -> object:
        node = self._node
        declared = ROS_TYPES[spec.kind]
        # rclpy keeps start-up overrides (-p, params files) only in this attribute, and checks
        # their type against the default's before any callback could convert them.
        overrides = node._parameter_overrides
        if name in overrides:
            overrides[name] = as_double(overrides[name], declared)
        value: object = declared if default is None else \
            list(default) if isinstance(default, tuple) else default
        if spec.kind == 'double' and isinstance(value, int) and not isinstance(value, bool):
            value = float(value)
        return node.declare_parameter(name, value, descriptor(spec, description)).value

    # Reading.
    def declared(self, name: str) -> bool:
        """Return whether ``name`` is declared on the node."""
        return bool(self._node.has_parameter(name))

    def current(self, names: Iterable[str]) -> ParameterRequest:
        """Return the current values of ``names`` as a request (to check them as one)."""
        return ParameterRequest([self._parameter(name) for name in names])

    def value(self, name: str) -> object:
        """Return the current value of a declared parameter (None: an unset array)."""
        return self._parameter(name).value

    def _parameter(self, name: str) -> Parameter:
        # rclpy's get_parameter refuses a typed parameter nobody set; that is None here.
        if not self._node.has_parameter(name):
            raise KeyError(f'{self.table.node_name}: {name!r} is not declared')
        return self._node.get_parameter_or(name, Parameter(name, value=None))

    def double(self, name: str) -> float:
        """Return a double parameter."""
        value = self._typed(name, 'double')
        assert isinstance(value, (int, float))
        return float(value)

    def period(self, name: str) -> SamplePeriod:
        """Return a double parameter that is a sample or control period, s."""
        return SamplePeriod(self.double(name))

    def integer(self, name: str) -> int:
        """Return an integer parameter."""
        value = self._typed(name, 'int')
        assert isinstance(value, int)
        return value

    def flag(self, name: str) -> bool:
        """Return a bool parameter."""
        return bool(self._typed(name, 'bool'))

    def text(self, name: str) -> str:
        """Return a string parameter."""
        return str(self._typed(name, 'string'))

    def texts(self, name: str) -> list[str] | None:
        """Return a string-array parameter (None if unset)."""
        value = self._typed(name, 'string_array')
        return None if value is None else [str(v) for v in array_items(value)]

    def doubles(self, name: str) -> list[float] | None:
        """Return a double-array parameter (None if unset)."""
        value = self._typed(name, 'double_array')
        return None if value is None else [float(v) for v in array_items(value)]

    def _typed(self, name: str, kind: str) -> object:
        spec = self.table.find(name)
        if spec is None or spec.kind != kind:
            raise TypeError(f'{self.table.node_name}: {name!r} is not a {kind} parameter')
        return self.value(name)

    # Checking and applying.
    @property
    def live(self) -> bool:
        """Whether :meth:`start` is done: set requests are checked and applied."""
        return self._started

    def start(self) -> None:
        """
        Check the declared values with the node's check, apply each once, then go live.

        Raises ConfigurationError if the node's check refuses the declared values.
        """
        declared = [self._parameter(spec.name) for spec in self.table.node_specs
                    if self._node.has_parameter(spec.name)]
        if self._check is not None:
            try:
                self._check(ParameterRequest(declared))
            except (HydroSdpError, TypeError, ValueError) as error:
                raise ConfigurationError(str(error)) from None
        for handler in dict.fromkeys(self._apply.values()):
            handler()
        self._started = True

    def _sized(self, answer: Callable[[Request, Response], Response], request: Request,
               response: Response) -> Response:
        # A set request of the services, refused on the sizes its message gives, before
        # rclpy reads a value of it; else answered as rclpy answers it.
        if len(request.parameters) > MAX_NAMES:
            reason = f'a request names at most {MAX_NAMES} parameters, got ' \
                     f'{len(request.parameters)}'
            if isinstance(response, SetParametersAtomically.Response):
                response.result = SetParametersResult(successful=False, reason=reason)
            else:
                response.results = [SetParametersResult(successful=False, reason=reason)]
            return response
        reasons: list[str | None] = []
        for message in request.parameters:
            if len(message.name) > MAX_CHARACTERS:
                reasons.append(f'a parameter name takes at most {MAX_CHARACTERS} characters, '
                               f'got {len(message.name)}')
                continue
            spec = self.table.find(message.name)
            value = message.value
            sized = value.string_value if spec is not None and spec.kind == 'string' else \
                max((value.double_array_value, value.integer_array_value, value.bool_array_value,
                     value.byte_array_value, value.string_array_value), key=len)
            reasons.append(None if spec is None else size_error(spec, sized, message.name))
        if not any(reasons):
            return answer(request, response)
        if isinstance(response, SetParametersAtomically.Response):
            response.result = SetParametersResult(
                successful=False, reason=next(reason for reason in reasons if reason))
            return response
        # One by one, as rclpy sets them: the others are set, or refused, on their own.
        kept = SetParameters.Request(parameters=[message for message, reason
                                                 in zip(request.parameters, reasons)
                                                 if not reason])
        results = iter(answer(kept, SetParameters.Response()).results)
        response.results = [SetParametersResult(successful=False, reason=reason) if reason
                            else next(results) for reason in reasons]
        return response

    @staticmethod
    def _listed(answer: Callable[[Queried, Answered], Answered], request: Queried,
                response: Answered) -> Answered:
        # A request of the reading services naming more parameters than a node has, or names
        # longer than any, is answered with nothing, as rclpy answers for names it lacks.
        names = request.prefixes if isinstance(request, ListParameters.Request) else request.names
        if len(names) > MAX_NAMES or any(len(name) > MAX_CHARACTERS for name in names):
            return response
        return answer(request, response)

    def _before_set(self, parameters: list[Parameter]) -> list[Parameter]:
        # Pre-set: a value too large is replaced by an empty one of its type (refused in
        # on-set, read no further); integers of double parameters as doubles; the twin of
        # every name set.
        self._oversized = ''
        converted = []
        for parameter in parameters:
            spec = self.table.find(parameter.name)
            if spec is None:
                converted.append(parameter)
                continue
            reason = size_error(spec, parameter.value, parameter.name)
            if reason:
                self._oversized = self._oversized or reason
                parameter = Parameter(parameter.name, parameter.type_,
                                      '' if spec.kind == 'string' else [])
            converted.append(as_double(parameter, ROS_TYPES[spec.kind]))
        named = {p.name for p in converted}
        twins = [Parameter(self._twins[p.name], p.type_, p.value) for p in converted
                 if p.name in self._twins and self._twins[p.name] not in named]
        return converted + twins

    def _on_set(self, parameters: list[Parameter]) -> SetParametersResult:
        # On-set: check the whole request; nothing is applied here.
        if self._oversized:
            return SetParametersResult(successful=False, reason=self._oversized)
        if self._started:
            clock = self._node.get_parameter('use_sim_time').value
            changed = [p for p in parameters if p.name == 'use_sim_time' and p.value != clock]
            if changed:
                return SetParametersResult(
                    successful=False, reason=f'use_sim_time is fixed at start-up (it is '
                    f'{str(clock).lower()}): a clock switched at run time would stop the '
                    "node's timers; restart the node with -p use_sim_time:=...")
        try:
            for parameter in parameters:
                spec = self.table.find(parameter.name)
                if spec is not None:
                    spec.check(parameter.value, parameter.name)
            if self._started and self._check is not None:
                self._check(ParameterRequest(parameters))
        except (HydroSdpError, TypeError, ValueError) as error:
            return SetParametersResult(successful=False, reason=str(error))
        return SetParametersResult(successful=True)

    def _after_set(self, parameters: list[Parameter]) -> None:
        # Post-set: the request was accepted whole; apply all of it, each handler once.
        if not self._started:
            return
        request = ParameterRequest(parameters)
        handlers = dict.fromkeys(self._apply[name] for name in request.names
                                 if name in self._apply)
        joint_names = {spec.name for spec in self.table.joint_specs}
        if self._apply_joint is not None and any(
                name in joint_names or name.split('.', 1)[-1] in joint_names
                for name in request.names):
            handlers[partial(self._apply_joint, request)] = None
        for handler in handlers:
            try:
                handler()
            except HydroSdpError as error:
                # The check let through what the handler refuses: a defect, reported, and
                # no reason to end the node.
                self._node.get_logger().error(f'a parameter change was accepted but could '
                                              f'not be applied: {error}')

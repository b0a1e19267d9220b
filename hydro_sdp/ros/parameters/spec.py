"""A node's parameters as one table: name, type, default, range, read-only, description."""

from __future__ import annotations

from dataclasses import dataclass
import math
from typing import Iterable, Literal, Sequence, Sized, Union

from hydro_sdp.core.errors import ConfigurationError

#: The ROS parameter types the nodes use (generate_parameter_library's names).
ParameterType = Literal['bool', 'int', 'double', 'string', 'double_array', 'string_array']

#: A parameter value as the nodes declare it (arrays as tuples in a table, lists on a node).
ParameterValue = Union[bool, int, float, str, Sequence[float], Sequence[str]]

_SCALARS: dict[str, tuple[type, ...]] = {'bool': (bool,), 'int': (int,), 'double': (float, int),
                                         'string': (str,)}
_NUMBER_WORDS = {1: 'one', 2: 'two', 3: 'three'}
#: Most values an array parameter takes, and most characters a string takes: a request
#: beyond them is refused on its size alone, before any value is read.
MAX_ITEMS = 64
MAX_CHARACTERS = 4096
#: Most parameters one request to a node's parameter services names.
MAX_NAMES = 1024
#: Most characters of a refused value a message shows.
_SHOWN = 80


def shown(value: object) -> str:
    """Return ``repr(value)``, cut to its start when long (a message quotes it)."""
    if isinstance(value, Sequence) and len(value) > _SHOWN:
        return f'{repr(value[:_SHOWN // 4])[:_SHOWN]}... ({len(value)} in all)'
    return repr(value)


@dataclass(frozen=True)
class ParameterSpec:
    """
    One parameter of a node.

    Parameters
    ----------
    name : str
        Parameter name; dots group it in YAML (``gains.k_i``).
    kind : ParameterType
        ROS type (generate_parameter_library's ``type``).
    description : str
        What it is and what a change does: the descriptor's text (``ros2 param describe``)
        and the documentation's.
    default : ParameterValue or None
        Default value; None when it has none (an unset array) or the node computes it at
        declaration (then ``default_text`` says what it is).
    default_text : str
        How the documentation shows a default the node computes (``designed``).
    unit : str
        Unit of the value (``s``, ``deg``, ``input units``), or '' for none.
    low, high : float or None
        Range of a number, both ends included (rclpy enforces it on every set).
    read_only : bool
        Whether it is fixed at start-up; every other parameter takes effect at run time.
    choices : tuple of str
        The values a string may take ('' for any).
    length : int or None
        The number of values an array must have (None for any).
    required : bool
        Whether a string must be given (the default '' is refused at start-up).
    per_joint : bool
        Declared once per joint at configuration, as ``<joint>.<name>`` (a node of one
        joint also keeps the plain ``<name>``, in step).
    on_demand : bool
        Declared by the node only where it applies (``joint``: a node of one joint), not
        with the others at start.

    """

    name: str
    kind: ParameterType
    description: str
    default: ParameterValue | None = None
    default_text: str = ''
    unit: str = ''
    low: float | None = None
    high: float | None = None
    read_only: bool = False
    choices: tuple[str, ...] = ()
    length: int | None = None
    required: bool = False
    per_joint: bool = False
    on_demand: bool = False

    def __post_init__(self) -> None:
        """Refuse a spec that contradicts itself (a table is code; this fails at import)."""
        if (self.low is None) != (self.high is None):
            raise ValueError(f'{self.name}: a range needs both ends')
        if self.low is not None and self.kind not in ('int', 'double'):
            raise ValueError(f'{self.name}: only numbers have a range')
        if self.choices and self.kind != 'string':
            raise ValueError(f'{self.name}: only strings have choices')
        if self.length is not None and not self.kind.endswith('_array'):
            raise ValueError(f'{self.name}: only arrays have a length')
        if self.default is None and not (self.default_text or self.kind.endswith('_array')):
            raise ValueError(f'{self.name}: a parameter without a default needs default_text')
        if self.default is not None:
            self._check_shape(self.default, self.name)

    @property
    def is_array(self) -> bool:
        """Whether the value is an array."""
        return self.kind.endswith('_array')

    def check(self, value: object, name: str | None = None) -> None:
        """Refuse a value that breaks the table: wrong type, length, choice, range, or a NaN."""
        self._check_shape(value, name or self.name)

    def _wrong(self, value: object, label: str) -> ConfigurationError:
        return ConfigurationError(f'parameter {label} must be {_type_text(self)}, '
                                  f'got {shown(value)}')

    def require(self, value: object) -> None:
        """Refuse an empty value of a required parameter (given nowhere at start-up)."""
        if self.required and value == '':
            raise ConfigurationError(f'parameter {self.name!r} is required ({self.description})')

    @property
    def documented(self) -> str:
        """Return the description with the unit, as ``ros2 param describe`` shows it."""
        return f'{self.description} [{self.unit}]' if self.unit else self.description

    def _check_shape(self, value: object, name: str) -> None:
        label = repr(name)
        if value is None:
            if self.is_array and self.default is None:
                return                      # an array left unset
            raise ConfigurationError(f'parameter {label} needs a value')
        items: list[object] = [value]
        if self.is_array:
            if isinstance(value, (str, bytes)) or not isinstance(value, Iterable):
                raise self._wrong(value, label)
            items = list(value)
        kinds = _SCALARS['double' if self.kind == 'double_array' else
                         'string' if self.kind == 'string_array' else self.kind]
        if not all(isinstance(item, kinds) and (self.kind == 'bool' or
                                                not isinstance(item, bool)) for item in items):
            raise self._wrong(value, label)
        if self.length is not None and len(items) != self.length:
            count = _NUMBER_WORDS.get(self.length, str(self.length))
            raise ConfigurationError(f'parameter {label} needs {count} numbers, '
                                     f'got {shown(value)}')
        numbers = [float(item) for item in items if isinstance(item, (int, float))]
        if self.kind in ('double', 'double_array') and not all(map(math.isfinite, numbers)):
            raise ConfigurationError(f'parameter {label} must be finite, got {shown(value)}')
        if self.low is not None and self.high is not None and not \
                self.low <= numbers[0] <= self.high:
            raise ConfigurationError(f'parameter {label} must be in [{self.low:g}, '
                                     f'{self.high:g}], got {shown(value)}')
        if self.choices and value not in self.choices:
            raise ConfigurationError(f'parameter {label} must be one of '
                                     f"{', '.join(self.choices)}, got {shown(value)}")


def size_error(spec: ParameterSpec, value: object, name: str) -> str | None:
    """
    Return why ``value`` is too large for ``spec``, or None; reads its length only.

    ``spec``: the table's row.
    ``value``: the value as rclpy gives it (a list, an ``array.array``, a string).
    """
    if spec.is_array and isinstance(value, Sized) and not isinstance(value, (str, bytes)):
        limit, what = max(spec.length or 0, MAX_ITEMS), 'values'
    elif spec.kind == 'string' and isinstance(value, str):
        limit, what = MAX_CHARACTERS, 'characters'
    else:
        return None
    if len(value) <= limit:
        return None
    return f'parameter {name!r} takes at most {limit} {what}, got {len(value)}'


def _type_text(spec: ParameterSpec) -> str:
    return {'bool': 'true or false', 'int': 'a whole number', 'double': 'a number',
            'string': 'a string', 'double_array': 'a list of numbers',
            'string_array': 'a list of strings'}[spec.kind]


@dataclass(frozen=True)
class ParameterTable:
    """
    Every parameter of one node, in the order the documentation lists them.

    Attributes
    ----------
    executable : str
        Console script (``controller_node``).
    node_name : str
        Default node name (``pip_controller``), the key of the node in parameter files.

    """

    executable: str
    node_name: str
    specs: tuple[ParameterSpec, ...]

    def __post_init__(self) -> None:
        """Refuse two specs of one name."""
        names = [spec.name for spec in self.specs]
        twice = sorted({name for name in names if names.count(name) > 1})
        if twice:
            raise ValueError(f'{self.node_name}: parameters declared twice: {twice}')

    def __getitem__(self, name: str) -> ParameterSpec:
        """Return the spec named ``name`` (a plain name, not ``<joint>.<name>``)."""
        for spec in self.specs:
            if spec.name == name:
                return spec
        raise KeyError(f'{self.node_name} has no parameter {name!r}')

    @property
    def names(self) -> list[str]:
        """Return every parameter name, in table order."""
        return [spec.name for spec in self.specs]

    @property
    def node_specs(self) -> tuple[ParameterSpec, ...]:
        """Return the specs declared once per node (those declared on demand too)."""
        return tuple(spec for spec in self.specs if not spec.per_joint)

    @property
    def joint_specs(self) -> tuple[ParameterSpec, ...]:
        """Return the specs declared once per joint."""
        return tuple(spec for spec in self.specs if spec.per_joint)

    def find(self, name: str) -> ParameterSpec | None:
        """
        Return the spec of a declared name, or None.

        ``name``: a plain name, or ``<joint>.<name>`` of a per-joint parameter.
        Returns: the spec, or None for a name the table does not hold (``use_sim_time``).
        """
        for spec in self.specs:
            if name == spec.name or spec.per_joint and name.endswith('.' + spec.name):
                return spec
        return None

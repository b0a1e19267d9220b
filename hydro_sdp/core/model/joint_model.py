"""The joint model: the model file of docs/interfaces.md section 1, frozen (methods 3)."""

from __future__ import annotations

from dataclasses import dataclass, field, replace
import math
from typing import Mapping

from hydro_sdp.core.arrays import FloatArray
from hydro_sdp.core.errors import ConfigurationError, ModelFileError
from hydro_sdp.core.model.effects import (
    DirectionDependentDelay, Effect, effect_from_mapping, effect_to_mapping, EFFECT_TYPES)
from hydro_sdp.core.model.static_maps import MAP_KINDS, MapKind, SdpMap, StaticMap
from hydro_sdp.core.model.static_maps.poly import PolyMap
from hydro_sdp.core.model.timing import delay_samples, SamplePeriod
from hydro_sdp.core.model.undetermined import Undetermined
from hydro_sdp.core.validation import (
    Document, read_document, require_float, require_ordered_pair)
import numpy as np

MODEL_FORMAT = 'hydro_sdp/model/v1'

_COMMON_KEYS = ('format', 'joint', 'command_topic', 'load_topic', 'kind', 'delay',
                'angle_limits', 'input_limits', 'undetermined')
_ALL_MAP_KEYS = tuple(dict.fromkeys(key for cls in MAP_KINDS.values() for key in cls.keys))


@dataclass(frozen=True)
class JointModel:
    """
    One hydraulic joint: static map, pure delay, end stops and effects.

    Parameters
    ----------
    joint : str
        Joint name as it appears in ``JointState.name``.
    static_map : StaticMap
        Command-to-velocity map; its ``kind`` is the model's kind.
    delay : float
        Pure time delay between command and motion, s.
    angle_limits : tuple[float, float] | None
        Hardware end stops, degrees (a side may be infinite), or ``None``.
    input_limits : tuple[float, float] | None
        Command range accepted by the valve interface, input units, or ``None``.
    effects : tuple[Effect, ...]
        Effects beyond the static map, at most one of each kind.
    command_topic : str or None
        Float64 topic the commands were recorded on; None: the bag readers' default.
    load_topic : str or None
        Float64 topic of the load a ``load_dependence`` effect was fitted on, or None.
    undetermined : tuple[Undetermined, ...]
        Parameters the data bound but do not pin (methods 13).

    See Also
    --------
    load_model, save_model : the model file.
    identify : a model from records.

    Examples
    --------
    >>> from hydro_sdp import load_model
    >>> model = load_model('config/brokk_j2.yaml')
    >>> model.joint, model.static_map.kind, model.delay
    ('j2', 'sdp', 0.15)

    """

    joint: str
    static_map: StaticMap
    delay: float
    angle_limits: tuple[float, float] | None = None
    input_limits: tuple[float, float] | None = None
    effects: tuple[Effect, ...] = field(default=())
    command_topic: str | None = None
    load_topic: str | None = None
    undetermined: tuple[Undetermined, ...] = field(default=())

    def __post_init__(self) -> None:
        if not isinstance(self.joint, str) or not self.joint.strip():
            raise ModelFileError(f"key 'joint': expected a non-empty name, got {self.joint!r}")
        for key in ('command_topic', 'load_topic'):
            topic = getattr(self, key)
            if topic is not None and (not isinstance(topic, str) or not topic.strip()
                                      or any(c.isspace() for c in topic)):
                raise ModelFileError(f"key '{key}': expected a topic name without spaces, "
                                     f'got {topic!r}')
        if not (math.isfinite(self.delay) and self.delay >= 0.0):
            raise ModelFileError(f"key 'delay': must be a finite number >= 0 s, got {self.delay}")
        names = [effect.name for effect in self.effects]
        if len(set(names)) != len(names):
            raise ModelFileError(f"key 'effects': an effect appears twice in {names}")
        # Keep effects in the canonical order so that equal models compare equal.
        order = list(EFFECT_TYPES)
        object.__setattr__(self, 'effects',
                           tuple(sorted(self.effects, key=lambda e: order.index(e.name))))
        dead_zone = self.static_map.dead_zone
        if dead_zone is not None and self.input_limits is not None:
            low, high = self.input_limits
            if dead_zone[0] < low or dead_zone[1] > high:
                raise ModelFileError(f"key 'dead_zone': {list(dead_zone)} lies outside "
                                     f'input_limits [{low}, {high}]')

    @property
    def kind(self) -> MapKind:
        """Model kind: the map family (``sdp``, ``sdp_dz``, ``linear``, ``pwl`` or ``poly``)."""
        return self.static_map.kind

    @property
    def dead_zone(self) -> tuple[float, float] | None:
        """Dead-zone edges in input units, or ``None`` for a map without one."""
        return self.static_map.dead_zone

    @property
    def rest_command(self) -> float:
        """Command that holds the joint, input units: 0 inside the dead-zone, else its middle."""
        if isinstance(self.static_map, PolyMap):
            return self.static_map.rest     # the map's own zero, 50 for duty resting at 50
        dead_zone = self.dead_zone
        if dead_zone is None or dead_zone[0] <= 0.0 <= dead_zone[1]:
            return 0.0
        return 0.5 * (dead_zone[0] + dead_zone[1])

    def rate(self, v: FloatArray | float) -> FloatArray:
        """Steady angular velocity (deg/s) for commands ``v`` (input units)."""
        return self.static_map.rate(np.asarray(v, dtype=np.float64))

    def alpha(self, dt: float) -> tuple[float, float, float, float, float, float]:
        """Return the first paper's ``alpha_1..alpha_6`` at ``dt`` s (``sdp``; SdpMap.alpha)."""
        if not isinstance(self.static_map, SdpMap):
            raise ConfigurationError(f'alpha is defined for kind sdp only, not {self.kind}')
        return self.static_map.alpha(SamplePeriod(dt))

    def delay_samples(self, dt: float) -> int:
        """Pure delay in whole samples at sample period ``dt``."""
        return delay_samples(self.delay, SamplePeriod(dt))

    def longest_delay_samples(self, dt: float) -> int:
        """Longest pure delay of either direction in whole samples (effects included)."""
        period = SamplePeriod(dt)
        split = self.effect(DirectionDependentDelay.name)
        if not isinstance(split, DirectionDependentDelay):
            return self.delay_samples(period)
        return max(self.delay_samples(period), delay_samples(split.positive, period),
                   delay_samples(split.negative, period))

    def effect(self, name: str) -> Effect | None:
        """Return the effect called ``name``, or ``None`` if the model has none."""
        for effect in self.effects:
            if effect.name == name:
                return effect
        return None

    def with_effect(self, effect: Effect) -> JointModel:
        """Return a copy with ``effect`` added, replacing one of the same name."""
        kept = tuple(e for e in self.effects if e.name != effect.name)
        return replace(self, effects=kept + (effect,))

    def without_effect(self, name: str) -> JointModel:
        """Return a copy without the effect called ``name``."""
        return replace(self, effects=tuple(e for e in self.effects if e.name != name))

    def to_mapping(self) -> dict[str, object]:
        """Return the model as the plain mapping of a model file (keys in interfaces.md order)."""
        data: dict[str, object] = {
            'format': MODEL_FORMAT,
            'joint': self.joint,
        }
        if self.command_topic is not None:
            data['command_topic'] = self.command_topic
        if self.load_topic is not None:
            data['load_topic'] = self.load_topic
        data.update({
            'kind': self.kind,
            'delay': self.delay,
            'angle_limits': None if self.angle_limits is None else [
                value if math.isfinite(value) else None for value in self.angle_limits],
            'input_limits': None if self.input_limits is None else list(self.input_limits),
        })
        data.update(self.static_map.to_mapping())
        data['effects'] = {effect.name: effect_to_mapping(effect) for effect in self.effects}
        if self.undetermined:
            data['undetermined'] = {entry.parameter: entry.to_mapping()
                                    for entry in self.undetermined}
        return data

    @classmethod
    def from_mapping(cls, data: object) -> JointModel:
        """
        Validate a mapping read from a model file and build the model.

        Raises
        ------
        ModelFileError
            Naming the key and the reason when anything is missing, unknown or invalid.

        """
        data = read_document(data, 'a model file', MODEL_FORMAT,
                             known=_COMMON_KEYS + _ALL_MAP_KEYS + ('effects',),
                             required=('format', 'joint', 'kind', 'delay'))
        kind = data['kind']
        if not isinstance(kind, str) or kind not in MAP_KINDS:
            raise ModelFileError(
                f"key 'kind': expected one of {', '.join(MAP_KINDS)}, got {kind!r}")
        map_cls = MAP_KINDS[kind]
        for key in _ALL_MAP_KEYS:
            if key in data and key not in map_cls.keys:
                raise ModelFileError(f'key {key!r} does not apply to kind {kind!r}')
        for key in map_cls.keys:
            if key not in data:
                raise ModelFileError(f'missing required key {key!r} for kind {kind!r}')
        effects = data.get('effects') or {}
        if not isinstance(effects, Mapping):
            raise ModelFileError("key 'effects': expected a mapping of effect name to parameters")
        bounds = data.get('undetermined') or {}
        if not isinstance(bounds, Mapping):
            raise ModelFileError("key 'undetermined': expected a mapping of parameter to bound")
        joint = data['joint']
        if not isinstance(joint, str):
            raise ModelFileError(f"key 'joint': expected a name, got {joint!r}")
        topics: dict[str, str | None] = {}
        for key in ('command_topic', 'load_topic'):
            topic = data.get(key)
            if topic is not None and not isinstance(topic, str):
                raise ModelFileError(f"key '{key}': expected a topic name, got {topic!r}")
            topics[key] = topic
        model = cls(
            joint=joint,
            static_map=map_cls.from_mapping(data),
            delay=require_float(data['delay'], 'delay'),
            angle_limits=_stops(data),
            input_limits=_optional_limits(data, 'input_limits'),
            effects=tuple(effect_from_mapping(str(name), params)
                          for name, params in effects.items()),
            command_topic=topics['command_topic'],
            load_topic=topics['load_topic'],
            undetermined=tuple(Undetermined.from_mapping(str(name), entry)
                               for name, entry in bounds.items()),
        )
        return model


def _stops(data: Document) -> tuple[float, float] | None:
    # A stop seen on one side only: the other is null in the file, infinite here.
    value = data.get('angle_limits')
    if isinstance(value, (list, tuple)) and len(value) == 2 and None in value:
        if value == [None, None] or value == (None, None):
            return None
        known = require_float(value[1] if value[0] is None else value[0], 'angle_limits')
        return (-math.inf, known) if value[0] is None else (known, math.inf)
    return _optional_limits(data, 'angle_limits')


def _optional_limits(data: Document, key: str) -> tuple[float, float] | None:
    value = data.get(key)
    return None if value is None else require_ordered_pair(value, key)

"""The signals file: which channels of a logger's file are a machine's joints and signals."""

from __future__ import annotations

from dataclasses import dataclass, field
import os
import re
from typing import Mapping

from hydro_sdp.core.errors import ConfigurationError
from hydro_sdp.core.validation import Document
from hydro_sdp.io.documents import load_yaml

#: Units of an angle channel.
ANGLE_UNITS = ('deg', 'rad')
#: Keys of the file, of a joint, in order.
FILE_KEYS = ('time', 'angle_unit', 'joints', 'signals')
JOINT_KEYS = ('angle', 'command', 'command_negative', 'angle_unit')
#: A joint name (a JointState name and the first part of its topics) and a topic name.
JOINT_NAME = re.compile(r'[A-Za-z][A-Za-z0-9_]*\Z')
TOPIC_NAME = re.compile(r'/?[A-Za-z_][A-Za-z0-9_]*(/[A-Za-z_][A-Za-z0-9_]*)*\Z')


@dataclass(frozen=True)
class JointChannels:
    """
    The channels of one joint.

    Attributes
    ----------
    command : str or None
        Command channel (None: the joint is only measured).
    command_negative : str or None
        Channel subtracted from ``command`` (one valve coil per direction).
    angle_unit : str
        ``deg`` or ``rad``.

    """

    angle: str
    command: str | None = None
    command_negative: str | None = None
    angle_unit: str = 'deg'


@dataclass(frozen=True)
class MachineSpec:
    """
    A machine's joints and signals in a logger's files.

    Attributes
    ----------
    joints : Mapping[str, JointChannels]
        Joints in order: the first joint's angle samples are the bag's time base.
    signals : Mapping[str, str]
        Float64 topic (with its leading slash) per channel.
    time : str or None
        Time column or variable, s (None: each channel's own time base, MDF4 only).

    """

    joints: Mapping[str, JointChannels]
    signals: Mapping[str, str] = field(default_factory=dict)
    time: str | None = None
    source: str = 'command line'


def _name(value: object, where: str) -> str:
    if isinstance(value, bool) or not isinstance(value, (str, int)) or str(value).strip() == '':
        raise ConfigurationError(f'{where}: expected a channel name, got {value!r}')
    return str(value)


def _unit(value: object, where: str) -> str:
    if value not in ANGLE_UNITS:
        raise ConfigurationError(f'{where}: angle unit must be deg or rad, got {value!r}')
    return str(value)


def _mapping(value: object, where: str, keys: tuple[str, ...]) -> Document:
    if not isinstance(value, Mapping):
        raise ConfigurationError(f'{where}: expected a mapping, got {type(value).__name__}')
    unknown = [str(key) for key in value if key not in keys]
    if unknown:
        raise ConfigurationError(f'{where}: unknown key {unknown[0]!r} (keys: '
                                 f"{', '.join(keys)})")
    return value


def _keys_of(value: object) -> tuple[str, ...]:
    # Anything but a mapping has no keys, and _mapping then refuses it by its type.
    return tuple(str(key) for key in value) if isinstance(value, Mapping) else ()


def spec_from_mapping(data: object, source: str) -> MachineSpec:
    """Build a :class:`MachineSpec` from a parsed signals file."""
    top = _mapping(data, source, FILE_KEYS)
    unit = _unit(top.get('angle_unit', 'deg'), f'{source}: angle_unit')
    joints_data = top.get('joints')
    if not joints_data:
        raise ConfigurationError(f'{source}: joints: at least one joint is needed')
    joints = {}
    for name, entry in _mapping(joints_data, f'{source}: joints', _keys_of(joints_data)).items():
        where = f'{source}: joints.{name}'
        if not JOINT_NAME.match(str(name)):
            raise ConfigurationError(f'{where}: a joint name is a letter, then letters, digits '
                                     'or _')
        if not isinstance(entry, Mapping) or 'angle' not in entry:
            raise ConfigurationError(f'{where}: no angle (every joint needs its angle channel)')
        entry = _mapping(entry, where, JOINT_KEYS)
        command = entry.get('command')
        negative = entry.get('command_negative')
        if negative is not None and command is None:
            raise ConfigurationError(f'{where}: command_negative without command')
        joints[str(name)] = JointChannels(
            _name(entry['angle'], f'{where}.angle'),
            None if command is None else _name(command, f'{where}.command'),
            None if negative is None else _name(negative, f'{where}.command_negative'),
            _unit(entry.get('angle_unit', unit), f'{where}.angle_unit'))
    signals = {}
    signals_data = top.get('signals') or {}
    for topic, channel in _mapping(signals_data, f'{source}: signals',
                                   _keys_of(signals_data)).items():
        where = f'{source}: signals.{topic}'
        if not TOPIC_NAME.match(str(topic)):
            raise ConfigurationError(f'{where}: not a topic name (letters, digits, _ and /)')
        signals['/' + str(topic).lstrip('/')] = _name(channel, where)
    commands = {f'/{joint}/valve_command' for joint, c in joints.items() if c.command}
    clash = sorted(commands & set(signals))
    if clash:
        raise ConfigurationError(f'{source}: signals.{clash[0].lstrip("/")}: is a command topic')
    time = top.get('time')
    return MachineSpec(joints, signals, None if time is None else _name(time, f'{source}: time'),
                       source)


def load_signals(path: str | os.PathLike[str]) -> MachineSpec:
    """Read a signals file."""
    return spec_from_mapping(load_yaml(path), str(path))


def single_joint_spec(joint: str, angle: str, command: str, *, time: str | None = None,
                      command_negative: str | None = None,
                      angle_unit: str = 'deg') -> MachineSpec:
    """Return the spec the single-joint options give (``--joint --time --angle --command``...)."""
    if not joint:
        raise ConfigurationError('joint name must not be empty')
    _unit(angle_unit, '--angle-unit')
    return MachineSpec({joint: JointChannels(angle, command, command_negative, angle_unit)},
                       {}, time)

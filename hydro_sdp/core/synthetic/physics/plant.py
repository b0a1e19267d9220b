"""A physics plant file (format ``hydro_sdp/physics/v1``): one pump and its joints (methods 11)."""

from __future__ import annotations

from dataclasses import dataclass, replace
import math

from hydro_sdp.core.errors import ModelFileError
from hydro_sdp.core.synthetic.physics.parameters import (
    Compressibility, Cylinder, Linkage, Load, number, Pump, section, Valve)
from hydro_sdp.core.validation import read_document, require_mapping

PHYSICS_FORMAT = 'hydro_sdp/physics/v1'


@dataclass(frozen=True)
class Joint:
    """
    One joint: valve, cylinder, linkage, load, end-stop compliance and sensor.

    Attributes
    ----------
    name : str
        Joint name as in ``JointState.name``.
    stop_frequency : float
        Natural frequency of the link on its end-stop compliance, Hz (``stop.frequency``).
    stop_damping : float
        Damping ratio of that mode (``stop.damping``), 0 < d < 1.
    noise : float
        Standard deviation of the angle sensor noise, degrees.
    compressibility : Compressibility or None
        The oil column; None: the pressures settle at every sample.

    """

    name: str
    valve: Valve
    cylinder: Cylinder
    linkage: Linkage
    load: Load
    stop_frequency: float
    stop_damping: float
    noise: float = 0.0
    compressibility: Compressibility | None = None

    keys = ('name', 'valve', 'cylinder', 'linkage', 'load', 'stop', 'noise', 'compressibility')

    @classmethod
    def from_mapping(cls, data: object, where: str) -> Joint:
        """Build from one entry of the ``joints`` list."""
        data = require_mapping(data, where, cls.keys)
        name = data.get('name')
        if not isinstance(name, str) or not name.strip():
            raise ModelFileError(f'key {where + ".name"!r}: expected a non-empty name, '
                                 f'got {name!r}')
        stop = section(data, 'stop', where, ('frequency', 'damping'))
        joint = cls(
            name=name,
            valve=Valve.from_mapping(section(data, 'valve', where, Valve.keys), where + '.valve'),
            cylinder=Cylinder.from_mapping(section(data, 'cylinder', where, Cylinder.keys),
                                           where + '.cylinder'),
            linkage=Linkage.from_mapping(section(data, 'linkage', where, Linkage.keys),
                                         where + '.linkage'),
            load=Load.from_mapping(section(data, 'load', where, Load.keys), where + '.load'),
            stop_frequency=number(stop, 'frequency', where + '.stop', low=0.0, strict_low=True),
            stop_damping=number(stop, 'damping', where + '.stop', low=0.0, strict_low=True,
                                high=0.99),
            noise=number(data, 'noise', where, low=0.0, default=0.0),
            compressibility=None if 'compressibility' not in data else
            Compressibility.from_mapping(section(data, 'compressibility', where,
                                                 Compressibility.keys),
                                         where + '.compressibility'))
        if joint.compressibility is not None and not joint.valve.compensated:
            raise ModelFileError(f'key {where + ".compressibility"!r}: needs a compensated '
                                 'valve (its meter-in flow is taken as the compensated one)')
        link = joint.linkage
        longest = link.base_distance + link.rod_distance
        shortest = abs(link.base_distance - link.rod_distance)
        cyl = joint.cylinder
        if cyl.min_length <= shortest or cyl.min_length + cyl.stroke >= longest:
            raise ModelFileError(
                f'key {where + ".cylinder.stroke"!r}: cylinder lengths {cyl.min_length}..'
                f'{cyl.min_length + cyl.stroke} mm must lie strictly between {shortest} and '
                f'{longest} mm, which the linkage can reach')
        return joint


@dataclass(frozen=True)
class Machine:
    """
    A physics plant: one pump and its joints.

    Attributes
    ----------
    joints : tuple[Joint, ...]
        The joints, in the order of the command columns.

    """

    pump: Pump
    joints: tuple[Joint, ...]

    @property
    def names(self) -> tuple[str, ...]:
        """Joint names in column order."""
        return tuple(joint.name for joint in self.joints)

    @classmethod
    def from_mapping(cls, data: object) -> Machine:
        """
        Validate a parsed physics file and build the machine.

        Raises ModelFileError naming the key when anything is missing, unknown or invalid.
        """
        data = read_document(data, 'a physics file', PHYSICS_FORMAT,
                             known=('format', 'pump', 'joints'))
        pump = Pump.from_mapping(section(data, 'pump', '', Pump.keys))
        joints = data.get('joints')
        if not isinstance(joints, list) or not joints:
            raise ModelFileError("key 'joints': expected a non-empty list of joints")
        built = tuple(Joint.from_mapping(entry, f'joints[{i}]') for i, entry in enumerate(joints))
        names = [joint.name for joint in built]
        if len(set(names)) != len(names):
            raise ModelFileError(f"key 'joints': joint names repeat in {names}")
        return cls(pump, built)


def with_payload(machine: Machine, payload: float, joint: int = 0) -> Machine:
    """Return a copy of the machine with ``payload`` (kg, >= 0) on joint index ``joint``."""
    if not (math.isfinite(payload) and payload >= 0.0):
        raise ModelFileError(f"key 'joints[{joint}].load.payload': must be >= 0, got {payload}")
    joints = list(machine.joints)
    changed = joints[joint]
    joints[joint] = replace(changed, load=replace(changed.load, payload=float(payload)))
    return replace(machine, joints=tuple(joints))

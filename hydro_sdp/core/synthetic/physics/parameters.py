"""
Sections of a physics plant file: pump, valve, cylinder, linkage and load (methods 11).

Values are in data-sheet units (mm, mm^2, bar, l/min, kg, degrees); an invalid value
is refused with an error naming the key.
"""

from __future__ import annotations

from dataclasses import dataclass
import math

from hydro_sdp.core.errors import ModelFileError
from hydro_sdp.core.validation import (
    Document, require_float, require_mapping, require_ordered_pair)


def number(data: Document, key: str, where: str, *, low: float = -math.inf,
           high: float = math.inf, strict_low: bool = False,
           default: float | None = None) -> float:
    """Read ``data[key]`` as a number within bounds; errors name ``where.key``."""
    name = f'{where}.{key}'
    if key not in data:
        if default is None:
            raise ModelFileError(f'missing required key {name!r}')
        return default
    value = require_float(data[key], name)
    if value < low or (strict_low and value == low) or value > high:
        lower = f'> {low}' if strict_low else f'>= {low}'
        bound = lower if math.isinf(high) else f'{lower} and <= {high}'
        raise ModelFileError(f'key {name!r}: must be {bound}, got {value}')
    return value


def section(data: Document, key: str, where: str,
            keys: tuple[str, ...]) -> Document:
    """Return the mapping under ``key``, refusing unknown keys inside it."""
    name = f'{where}.{key}' if where else key
    if key not in data:
        raise ModelFileError(f'missing required key {name!r}')
    return require_mapping(data[key], name, keys)


@dataclass(frozen=True)
class Pump:
    """
    Load-sensing pump with flow sharing and a power (torque) limit, shared by all joints.

    Parameters
    ----------
    flow : float
        Largest total flow, l/min; above it every joint's flow is scaled alike.
    margin : float
        Load-sensing margin across each meter-in orifice, bar.
    relief_pressure : float
        Main relief, bar.
    tank_pressure : float
        Return line pressure, bar.
    oil_density : float
        Oil density, kg/m^3.
    power : float
        Largest hydraulic power, kW (0: no limit); flow at pressure ``p`` <= ``power / p``.

    """

    flow: float
    margin: float
    relief_pressure: float
    tank_pressure: float = 2.0
    oil_density: float = 860.0
    power: float = 0.0

    keys = ('flow', 'margin', 'relief_pressure', 'tank_pressure', 'oil_density', 'power')

    def available(self, pressure: float) -> float:
        """Return the flow the pump gives at ``pressure`` (Pa), m^3/s."""
        largest = self.flow * 1e-3 / 60.0
        if self.power > 0.0 and pressure > 0.0:
            return min(largest, self.power * 1e3 / pressure)
        return largest

    @classmethod
    def from_mapping(cls, data: Document) -> Pump:
        """Build from the ``pump`` section of a file."""
        pump = cls(flow=number(data, 'flow', 'pump', low=0.0, strict_low=True),
                   margin=number(data, 'margin', 'pump', low=0.0, strict_low=True),
                   relief_pressure=number(data, 'relief_pressure', 'pump', low=0.0,
                                          strict_low=True),
                   tank_pressure=number(data, 'tank_pressure', 'pump', low=0.0, default=2.0),
                   oil_density=number(data, 'oil_density', 'pump', low=0.0, strict_low=True,
                                      default=860.0),
                   power=number(data, 'power', 'pump', low=0.0, default=0.0))
        if pump.relief_pressure <= pump.margin + pump.tank_pressure:
            raise ModelFileError("key 'pump.relief_pressure': must exceed margin + tank_pressure")
        return pump


@dataclass(frozen=True)
class Valve:
    """
    Proportional spool valve of one joint.

    Attributes
    ----------
    neutral : float
        Command at which the spool is centred, command units.
    limits : tuple[float, float]
        Commands driving the spool fully each way (clipped beyond); above ``neutral`` extends.
    overlap : float
        Spool overlap, fraction of full travel 0..1 (the dead-zone).
    dead_time : float
        Pure delay of the electronics and pilot stage, s.
    time_constant : float
        First-order lag of the spool, s.
    opening : tuple[tuple[float, float], ...]
        Metering notch: (travel fraction, meter-in area mm^2) pairs, linear between.
    outlet_ratio : float
        Meter-out area over meter-in area at the same spool travel.
    retract_ratio : float
        Areas of the retracting side's notches over those of ``opening``.
    compensated : bool
        Whether a pressure compensator holds the pump's margin across the meter-in edge.

    """

    neutral: float
    limits: tuple[float, float]
    overlap: float
    dead_time: float
    time_constant: float
    discharge_coefficient: float
    opening: tuple[tuple[float, float], ...]
    outlet_ratio: float = 1.0
    retract_ratio: float = 1.0
    compensated: bool = True

    keys = ('neutral', 'limits', 'overlap', 'dead_time', 'time_constant',
            'discharge_coefficient', 'opening', 'outlet_ratio', 'retract_ratio', 'compensated')

    @classmethod
    def from_mapping(cls, data: Document, where: str) -> Valve:
        """Build from a joint's ``valve`` section."""
        neutral = number(data, 'neutral', where)
        if 'limits' not in data:
            raise ModelFileError(f'missing required key {where + ".limits"!r}')
        limits = require_ordered_pair(data['limits'], f'{where}.limits')
        if not limits[0] < neutral < limits[1]:
            raise ModelFileError(f'key {where + ".neutral"!r}: must lie strictly inside '
                                 f'limits [{limits[0]}, {limits[1]}], got {neutral}')
        overlap = number(data, 'overlap', where, low=0.0, high=0.95)
        return cls(neutral=neutral, limits=limits, overlap=overlap,
                   dead_time=number(data, 'dead_time', where, low=0.0),
                   time_constant=number(data, 'time_constant', where, low=0.0),
                   discharge_coefficient=number(data, 'discharge_coefficient', where,
                                                low=0.0, strict_low=True, high=1.0),
                   opening=_opening(data, f'{where}.opening', overlap),
                   outlet_ratio=number(data, 'outlet_ratio', where, low=0.0,
                                       strict_low=True, default=1.0),
                   retract_ratio=number(data, 'retract_ratio', where, low=0.0,
                                        strict_low=True, default=1.0),
                   compensated=_flag(data, 'compensated', where, default=True))


def _flag(data: Document, key: str, where: str, *, default: bool) -> bool:
    """Read ``data[key]`` as true or false; errors name ``where.key``."""
    value = data.get(key, default)
    if not isinstance(value, bool):
        raise ModelFileError(f'key {where + "." + key!r}: expected true or false, got '
                             f'{value!r}')
    return value


def _opening(data: Document, name: str, overlap: float
             ) -> tuple[tuple[float, float], ...]:
    if 'opening' not in data:
        raise ModelFileError(f'missing required key {name!r}')
    table = data['opening']
    if not isinstance(table, (list, tuple)) or not table:
        raise ModelFileError(f'key {name!r}: expected a list of [travel, area] pairs')
    rows = []
    for i, row in enumerate(table):
        if not isinstance(row, (list, tuple)) or len(row) != 2:
            raise ModelFileError(f'key {name}[{i}]: expected a pair [travel, area]')
        rows.append((require_float(row[0], f'{name}[{i}][0]'),
                     require_float(row[1], f'{name}[{i}][1]')))
    travels = [overlap] + [row[0] for row in rows]
    areas = [0.0] + [row[1] for row in rows]
    for i in range(len(rows)):
        if travels[i + 1] <= travels[i]:
            raise ModelFileError(f'key {name}[{i}][0]: spool travel must increase from the '
                                 f'overlap {overlap}, got {travels[i + 1]}')
        if areas[i + 1] < areas[i] or areas[i + 1] <= 0.0:
            raise ModelFileError(f'key {name}[{i}][1]: area must be positive and '
                                 f'non-decreasing, got {areas[i + 1]}')
    if travels[-1] != 1.0:
        raise ModelFileError(f'key {name}: the last spool travel must be 1.0, got {travels[-1]}')
    return tuple(rows)


@dataclass(frozen=True)
class Cylinder:
    """
    Double-acting cylinder with end-of-stroke cushions.

    Attributes
    ----------
    bore : float
        Piston diameter, mm.
    rod : float
        Rod diameter, mm.
    min_length : float
        Pin-to-pin length fully retracted, mm.
    cushion_length : float
        Length of each cushion at the stroke ends, mm.
    cushion_area : float
        Rod-end cushion bleed area at the end of the stroke, mm^2.
    cushion_entry_area : float
        Cushion area where the cushion begins, mm^2 (shrinks linearly to ``cushion_area``).
    friction : float
        Seal friction force, N.

    """

    bore: float
    rod: float
    min_length: float
    stroke: float
    cushion_length: float
    cushion_area: float
    cushion_entry_area: float
    friction: float = 0.0

    keys = ('bore', 'rod', 'min_length', 'stroke', 'cushion_length', 'cushion_area',
            'cushion_entry_area', 'friction')

    @classmethod
    def from_mapping(cls, data: Document, where: str) -> Cylinder:
        """Build from a joint's ``cylinder`` section."""
        bore = number(data, 'bore', where, low=0.0, strict_low=True)
        rod = number(data, 'rod', where, low=0.0, strict_low=True)
        if rod >= bore:
            raise ModelFileError(f'key {where + ".rod"!r}: must be below the bore {bore}, '
                                 f'got {rod}')
        stroke = number(data, 'stroke', where, low=0.0, strict_low=True)
        cushion_area = number(data, 'cushion_area', where, low=0.0, strict_low=True)
        cushion_entry_area = number(data, 'cushion_entry_area', where, low=cushion_area,
                                    strict_low=True)
        return cls(bore=bore, rod=rod,
                   min_length=number(data, 'min_length', where, low=0.0, strict_low=True),
                   stroke=stroke,
                   cushion_length=number(data, 'cushion_length', where, low=0.0,
                                         high=0.5 * stroke),
                   cushion_area=cushion_area, cushion_entry_area=cushion_entry_area,
                   friction=number(data, 'friction', where, low=0.0, default=0.0))


@dataclass(frozen=True)
class Linkage:
    """
    Triangle of the joint pivot and the cylinder's two pivots.

    Parameters
    ----------
    base_distance : float
        Joint pivot to cylinder base pivot, mm.
    rod_distance : float
        Joint pivot to rod-end pivot, mm.
    angle_offset : float
        The triangle's angle at the joint pivot minus the joint angle, degrees.

    """

    base_distance: float
    rod_distance: float
    angle_offset: float

    keys = ('base_distance', 'rod_distance', 'angle_offset')

    @classmethod
    def from_mapping(cls, data: Document, where: str) -> Linkage:
        """Build from a joint's ``linkage`` section."""
        return cls(base_distance=number(data, 'base_distance', where, low=0.0, strict_low=True),
                   rod_distance=number(data, 'rod_distance', where, low=0.0, strict_low=True),
                   angle_offset=number(data, 'angle_offset', where))


@dataclass(frozen=True)
class Load:
    """
    Gravity load of the link and its payload.

    Parameters
    ----------
    mass : float
        Link mass, kg.
    distance : float
        Joint pivot to the link's centre of mass, mm.
    payload : float
        Payload mass, kg.
    payload_distance : float
        Joint pivot to the payload, mm.
    phase : float
        Angle of the centre of mass above horizontal at joint angle 0, degrees.

    """

    mass: float
    distance: float
    payload: float
    payload_distance: float
    phase: float

    keys = ('mass', 'distance', 'payload', 'payload_distance', 'phase')

    @classmethod
    def from_mapping(cls, data: Document, where: str) -> Load:
        """Build from a joint's ``load`` section."""
        return cls(mass=number(data, 'mass', where, low=0.0),
                   distance=number(data, 'distance', where, low=0.0),
                   payload=number(data, 'payload', where, low=0.0, default=0.0),
                   payload_distance=number(data, 'payload_distance', where, low=0.0,
                                           default=0.0),
                   phase=number(data, 'phase', where, default=0.0))


@dataclass(frozen=True)
class Compressibility:
    """
    Oil compressibility and link inertia: the link rings on the oil column (methods 11).

    Parameters
    ----------
    bulk_modulus : float
        Effective bulk modulus of the oil with its hoses, bar.
    dead_volume_piston, dead_volume_rod : float
        Oil between the valve and each chamber at its end of stroke, cm^3 (> 0).
    inertia : float
        Link and payload inertia about the joint, kg m^2 (0: point masses of the load).
    viscous_friction : float
        Viscous friction of the seals, N s/m of cylinder speed.

    """

    bulk_modulus: float
    dead_volume_piston: float
    dead_volume_rod: float
    inertia: float = 0.0
    viscous_friction: float = 0.0

    keys = ('bulk_modulus', 'dead_volume_piston', 'dead_volume_rod', 'inertia',
            'viscous_friction')

    @classmethod
    def from_mapping(cls, data: Document, where: str) -> Compressibility:
        """Build from a joint's ``compressibility`` section."""
        return cls(bulk_modulus=number(data, 'bulk_modulus', where, low=0.0, strict_low=True),
                   dead_volume_piston=number(data, 'dead_volume_piston', where, low=0.0,
                                             strict_low=True),
                   dead_volume_rod=number(data, 'dead_volume_rod', where, low=0.0,
                                          strict_low=True),
                   inertia=number(data, 'inertia', where, low=0.0, default=0.0),
                   viscous_friction=number(data, 'viscous_friction', where, low=0.0,
                                           default=0.0))

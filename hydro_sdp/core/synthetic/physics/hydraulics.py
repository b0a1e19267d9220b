"""
Quasi-static hydraulics of one valve-and-cylinder: speed, pump flow, pressures (methods 11).

Orifice flow at both metering edges with the force balance on the piston; load-sensing,
relief-limited, cavitating and uncompensated cases as methods 11 describes.
"""

from __future__ import annotations

import math
from typing import Callable

from hydro_sdp.core.synthetic.physics.linkage import Geometry
from hydro_sdp.core.synthetic.physics.parameters import Pump
from hydro_sdp.core.synthetic.physics.plant import Joint

BAR = 1e5
# mm to m, mm^2 to m^2.
_MM = 1e-3
_MM2 = 1e-6


class Actuator:
    """
    One joint's valve metering edges, cylinder and load, in SI units.

    ``pump``: the machine's pump.
    """

    def __init__(self, joint: Joint, pump: Pump) -> None:
        cylinder = joint.cylinder
        self.geometry = Geometry(joint)
        self.piston = math.pi / 4.0 * (cylinder.bore * _MM) ** 2
        self.annulus = self.piston - math.pi / 4.0 * (cylinder.rod * _MM) ** 2
        self.stroke = cylinder.stroke * _MM
        self.cushion_length = cylinder.cushion_length * _MM
        cd = joint.valve.discharge_coefficient
        self.cushion_area = cd * cylinder.cushion_area * _MM2
        self.cushion_entry_area = cd * cylinder.cushion_entry_area * _MM2
        self.head_scale = (self.piston / self.annulus) ** 2
        self.friction = cylinder.friction
        self.outlet_ratio = joint.valve.outlet_ratio
        self.half_rho = 0.5 * pump.oil_density
        self.margin_speed = math.sqrt(2.0 * pump.margin * BAR / pump.oil_density)
        self.relief = pump.relief_pressure * BAR
        self.tank = pump.tank_pressure * BAR
        self.margin = pump.margin * BAR
        self.compensated = joint.valve.compensated

    def _sides(self, area: float, extension: float) -> tuple[float, float, float, float, float]:
        """Inlet and outlet chamber areas, resisting force, meter-in and meter-out areas."""
        area_sign = area
        if area > 0.0:
            inlet, outlet, to_end = self.piston, self.annulus, self.stroke - extension
            force = self.geometry.load_force(extension)
        else:
            inlet, outlet, to_end = self.annulus, self.piston, extension
            force = -self.geometry.load_force(extension)
            area = -area
        out_area = area * self.outlet_ratio
        if to_end < self.cushion_length:
            # Head-end cushions are scaled so both ends brake to the same speed at relief.
            scale = 1.0 if area_sign > 0.0 else self.head_scale
            cushion = scale * (self.cushion_area + (self.cushion_entry_area - self.cushion_area)
                               * max(to_end, 0.0) / self.cushion_length)
            # Two orifices in series: 1/A^2 adds.
            out_area = out_area * cushion / math.sqrt(out_area * out_area + cushion * cushion)
        return inlet, outlet, force + self.friction, area, out_area

    def blocked(self, area: float, extension: float) -> bool:
        """Whether the cylinder cannot move: spool closed, or driving into the end it is at."""
        return area == 0.0 or (area > 0.0 and extension >= self.stroke) or (
            area < 0.0 and extension <= 0.0)

    def demand(self, area: float, extension: float) -> tuple[float, float]:
        """
        Cylinder speed (m/s, signed) and pump flow (m^3/s) before flow sharing.

        ``area``: signed effective meter-in area ``Cd A``, m^2 (positive extends).
        ``extension``: cylinder extension, m.
        Returns: speed, m/s, and the flow drawn from the pump, m^3/s.
        """
        if self.blocked(area, extension):
            return 0.0, 0.0
        inlet, outlet, force, a_in, a_out = self._sides(area, extension)
        speed = a_in * self.margin_speed / inlet
        pumped = speed * inlet
        k_out = self.half_rho * outlet ** 3 / (a_out * a_out)
        drive = self.relief * inlet - self.tank * outlet - force
        if drive <= 0.0:
            return 0.0, 0.0
        at_relief = math.sqrt(drive / (self.half_rho * inlet ** 3 / (a_in * a_in) + k_out))
        if at_relief < speed:
            speed = at_relief
            pumped = speed * inlet
        elif force + self.tank * outlet + k_out * speed * speed < 0.0:
            speed = math.sqrt(-(force + self.tank * outlet) / k_out)
        return (speed if area > 0.0 else -speed), pumped

    def supplied(self, area: float, extension: float, supply: float) -> tuple[float, float]:
        """Cylinder speed and flow through a meter-in edge without compensation."""
        return self.supplied_at(area, extension)(supply)

    def supplied_at(self, area: float, extension: float
                    ) -> Callable[[float], tuple[float, float]]:
        """
        :meth:`supplied` at one area and extension, as a function of the pump pressure (Pa).

        ``area``: signed effective meter-in area ``Cd A``, m^2 (positive extends).
        ``extension``: cylinder extension, m.
        Returns: pump pressure to speed and flow, as :meth:`supplied` gives.
        """
        if self.blocked(area, extension):
            return lambda supply: (0.0, 0.0)
        inlet, outlet, force, a_in, a_out = self._sides(area, extension)
        k_out = self.half_rho * outlet ** 3 / (a_out * a_out)
        held = self.tank * outlet
        resisted = self.half_rho * inlet ** 3 / (a_in * a_in) + k_out

        def at(supply: float) -> tuple[float, float]:
            drive = min(supply, self.relief) * inlet - held - force
            if drive <= 0.0:
                return 0.0, 0.0
            speed = math.sqrt(drive / resisted)
            if force + held + k_out * speed * speed < 0.0:
                # An overrunning load pulls the inlet below 0 bar: the outlet edge sets the speed.
                speed = min(speed, math.sqrt(-(force + held) / k_out))
            return (speed if area > 0.0 else -speed), speed * inlet
        return at

    def inlet_pressure(self, area: float, extension: float, speed: float) -> float:
        """
        Pressure (Pa, at least 0) the inlet chamber needs to move at ``speed`` (force balance).

        ``area``: signed effective meter-in area, m^2.
        ``extension``: cylinder extension, m.
        ``speed``: cylinder speed, m/s.
        Returns: ``(F + p_out A_out) / A_in``, Pa.
        """
        inlet, outlet, force, _, a_out = self._sides(area, extension)
        outflow = self.tank + self.half_rho * (outlet * speed / a_out) ** 2
        return max((force + outlet * outflow) / inlet, 0.0)

    def pressures(self, area: float, extension: float, speed: float) -> tuple[float, float]:
        """
        Piston-side and rod-side pressures ``(p_piston, p_rod)``, bar.

        ``area``: signed effective meter-in area, m^2.
        ``extension``: cylinder extension, m.
        ``speed``: cylinder speed, m/s (after flow sharing).
        Returns: ``(p_piston, p_rod)``, bar.
        """
        if area == 0.0:
            # Closed spool: the trapped oil holds the load on one side.
            force = self.geometry.load_force(extension)
            if force > 0.0:
                return (force + self.tank * self.annulus) / self.piston / BAR, self.tank / BAR
            return self.tank / BAR, (self.tank * self.piston - force) / self.annulus / BAR
        inlet, outlet, force, _, a_out = self._sides(area, extension)
        if speed == 0.0:
            p_in, p_out = self.relief, self.tank
        else:
            p_out = min(self.tank + self.half_rho * (outlet * speed / a_out) ** 2, self.relief)
            p_in = min(max((force + outlet * p_out) / inlet, 0.0), self.relief)
        return (p_in / BAR, p_out / BAR) if area > 0.0 else (p_out / BAR, p_in / BAR)

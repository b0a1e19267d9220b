"""The link on a compressible oil column: pressures and link speed as states (methods 11)."""

from __future__ import annotations

import math

from hydro_sdp.core.synthetic.physics.hydraulics import Actuator, BAR
from hydro_sdp.core.synthetic.physics.plant import Joint

# cm^3 to m^3, mm to m.
_CM3 = 1e-6
_MM = 1e-3
#: Pressure below which an orifice's flow turns laminar (linear in the drop), Pa.
LAMINAR = 0.5 * BAR
#: Cylinder speed over which Coulomb friction builds up, m/s (a smooth sign).
STICTION_SPEED = 0.001
#: Longest sub-step, s, and its largest share of the fastest time constant.
LONGEST_STEP = 1e-3
STEP_SHARE = 0.1


def joint_inertia(joint: Joint) -> float:
    """Return the link's moment of inertia about its pivot, kg m^2 (the file's, or points)."""
    oil = joint.compressibility
    if oil is not None and oil.inertia > 0.0:
        return oil.inertia
    load = joint.load
    return (load.mass * (load.distance * _MM) ** 2
            + load.payload * (load.payload_distance * _MM) ** 2)


class OilColumn:
    """
    One joint's chambers and link as a dynamic system.

    ``actuator``: its valve edges, cylinder and load in SI units.
    ``extension``: cylinder extension at rest at the start, m.
    """

    def __init__(self, joint: Joint, actuator: Actuator, extension: float) -> None:
        oil = joint.compressibility
        if oil is None:
            raise ValueError(f'joint {joint.name!r} has no compressibility section')
        self.actuator = actuator
        self.geometry = actuator.geometry
        self.beta = oil.bulk_modulus * BAR
        self.dead_piston = oil.dead_volume_piston * _CM3
        self.dead_rod = oil.dead_volume_rod * _CM3
        self.viscous = oil.viscous_friction
        self.inertia = joint_inertia(joint)
        if not self.inertia > 0.0:
            raise ValueError(f'joint {joint.name!r}: the link has no inertia')
        self.friction = joint.cylinder.friction
        self.low, self.high = self.geometry.gamma(0.0), self.geometry.gamma(actuator.stroke)
        self.gamma = self.geometry.gamma(extension)
        self.rate = 0.0
        # At rest the trapped oil holds the load (the closed spool's pressures).
        piston, rod = actuator.pressures(0.0, extension, 0.0)
        self.p_piston, self.p_rod = piston * BAR, rod * BAR
        self._orifice = math.sqrt(2.0 / (2.0 * actuator.half_rho))

    @property
    def extension(self) -> float:
        """Cylinder extension, m."""
        return self._extension(self.gamma)

    def _extension(self, gamma: float) -> float:
        g = self.geometry
        length = math.sqrt(g.a * g.a + g.b * g.b - 2.0 * g.a * g.b * math.cos(gamma))
        return min(max(length - g.min_length, 0.0), self.actuator.stroke)

    def stiffness(self, extension: float) -> float:
        """Return the oil column's stiffness ``beta (A_a^2 / V_a + A_b^2 / V_b)``, N/m."""
        act = self.actuator
        volume_piston = self.dead_piston + act.piston * extension
        volume_rod = self.dead_rod + act.annulus * (act.stroke - extension)
        return self.beta * (act.piston ** 2 / volume_piston + act.annulus ** 2 / volume_rod)

    def natural_frequency(self, extension: float) -> float:
        """Return the hydraulic natural frequency ``sqrt(k_h r^2 / J) / 2 pi`` there, Hz."""
        arm = self.geometry.moment_arm(extension)
        return math.sqrt(self.stiffness(extension) * arm * arm / self.inertia) / (2.0 * math.pi)

    def damping_ratio(self, extension: float) -> float:
        """Return the viscous friction's damping ratio ``c / (2 sqrt(k_h J / r^2))`` there."""
        arm = self.geometry.moment_arm(extension)
        return self.viscous / (2.0 * math.sqrt(self.stiffness(extension) * self.inertia)
                               / arm)

    def _substeps(self, dt: float, outlet: float) -> int:
        """Sub-steps per sample: short against the mode and each chamber's orifice."""
        act = self.actuator
        least = min(self.dead_piston, self.dead_rod)
        fastest = 2.0 * math.pi * max(self.natural_frequency(0.0),
                                      self.natural_frequency(act.stroke))
        # The orifice's flow per pascal at its steepest (laminar) over the smallest chamber.
        arm = max(self.geometry.moment_arm(s) for s in (0.0, 0.5 * act.stroke, act.stroke))
        fastest = max(fastest, self.beta / least * outlet * self._orifice / math.sqrt(LAMINAR),
                      (self.friction / STICTION_SPEED + self.viscous) * arm * arm / self.inertia)
        step = min(LONGEST_STEP, STEP_SHARE / fastest) if fastest > 0.0 else LONGEST_STEP
        return max(1, int(math.ceil(dt / step)))

    def _flow(self, area: float, drop: float) -> float:
        """Flow through an orifice of effective area ``area``, m^3/s, turbulent above LAMINAR."""
        return area * self._orifice * drop / math.sqrt(math.sqrt(drop * drop + LAMINAR * LAMINAR))

    def advance(self, area: float, speed: float, dt: float) -> float:
        """
        Move the link over one sample; return the cylinder's extension then, m.

        ``area``: signed effective meter-in area of the valve, m^2 (0: closed).
        ``speed``: cylinder speed the valve and pump pass at settled pressures, m/s.
        ``dt``: sample period, s.
        """
        act, geometry = self.actuator, self.geometry
        extension = self.extension
        if area == 0.0:
            inflow, outlet = 0.0, 0.0
        else:
            inlet, _, _, _, outlet = act._sides(area, extension)
            inflow = abs(speed) * inlet
        steps = self._substeps(dt, abs(outlet))
        h = dt / steps
        beta, tank, relief = self.beta, act.tank, act.relief
        piston, annulus, stroke = act.piston, act.annulus, act.stroke
        for _ in range(steps):
            arm = geometry.moment_arm(extension)
            velocity = arm * self.rate
            if area > 0.0:
                into_piston = inflow
                into_rod = -self._flow(outlet, self.p_rod - tank)
            elif area < 0.0:
                into_piston = -self._flow(outlet, self.p_piston - tank)
                into_rod = inflow
            else:
                into_piston = into_rod = 0.0
            volume_piston = self.dead_piston + piston * extension
            volume_rod = self.dead_rod + annulus * (stroke - extension)
            self.p_piston += h * beta / volume_piston * (into_piston - piston * velocity)
            self.p_rod += h * beta / volume_rod * (into_rod + annulus * velocity)
            self.p_piston = min(max(self.p_piston, 0.0), relief)
            self.p_rod = min(max(self.p_rod, 0.0), relief)
            force = (self.p_piston * piston - self.p_rod * annulus
                     - geometry.load_force(extension) - self.viscous * velocity
                     - self.friction * math.tanh(velocity / STICTION_SPEED))
            self.rate += h * arm * force / self.inertia
            self.gamma += h * self.rate
            if self.gamma <= self.low or self.gamma >= self.high:
                # The cylinder stops dead at its stroke end.
                self.gamma = min(max(self.gamma, self.low), self.high)
                self.rate = 0.0
            extension = self._extension(self.gamma)
        return extension

    @property
    def pressures(self) -> tuple[float, float]:
        """Piston-side and rod-side pressures now, bar."""
        return self.p_piston / BAR, self.p_rod / BAR

"""
What the pump gives the valves: flow sharing, the power limit, valves without compensation.

The pump's pressure, flow and the valves' shares as methods 11 (Pump) describes.
"""

from __future__ import annotations

from typing import Callable, Sequence

from hydro_sdp.core.synthetic.physics.hydraulics import Actuator
from hydro_sdp.core.synthetic.physics.parameters import Pump

#: Speed, m/s, and flow, m^3/s, of one joint.
Flow = tuple[float, float]
#: Bisection steps on the pump pressure (a relative precision of 2^-50).
STEPS = 50


def _passed(actuators: Sequence[Actuator], curves: Sequence[Callable[[float], Flow]],
            demands: Sequence[Flow], supply: float) -> list[Flow]:
    """Speed and flow of every joint at a pump pressure (``curves``: their supplied_at)."""
    out = []
    for act, curve, demand in zip(actuators, curves, demands):
        passed = curve(supply)
        if act.compensated and abs(demand[0]) <= abs(passed[0]):
            passed = demand
        out.append(passed)
    return out


def speeds(actuators: Sequence[Actuator], pump: Pump, areas: Sequence[float],
           extensions: Sequence[float]) -> list[float]:
    """Return every cylinder's speed, m/s (signed), with the pump shared (methods 11)."""
    return Supply(actuators, pump).speeds(areas, extensions)


class Supply:
    """The pump and the joints it feeds, for :func:`speeds` sample after sample."""

    def __init__(self, actuators: Sequence[Actuator], pump: Pump) -> None:
        self.actuators = list(actuators)
        self.pump = pump
        self.compensated = all(act.compensated for act in self.actuators)
        #: The pump's flow, m^3/s, when the pressure changes nothing (else None).
        self.largest = pump.available(0.0) if self.compensated and pump.power <= 0.0 else None

    def speeds(self, areas: Sequence[float], extensions: Sequence[float]) -> list[float]:
        """Return every cylinder's speed, m/s: :func:`speeds` of these joints and pump."""
        actuators, pump, largest = self.actuators, self.pump, self.largest
        if largest is not None and len(actuators) == 1:
            # One joint, its valve compensated: its demand, scaled if the pump is short.
            speed, flow = actuators[0].demand(areas[0], extensions[0])
            return [speed * (largest / flow) if flow > largest else speed]
        demands = [act.demand(area, s) for act, area, s in zip(actuators, areas, extensions)]
        total = sum(flow for _, flow in demands)
        if largest is not None:
            share = largest / total if total > largest else 1.0
            return [speed * share for speed, _ in demands]
        compensated = self.compensated
        moving = [i for i, (speed, _) in enumerate(demands) if speed != 0.0]
        if not moving and compensated:
            return [0.0] * len(actuators)
        act0 = actuators[0]
        needed = [actuators[i].inlet_pressure(areas[i], extensions[i], abs(demands[i][0]))
                  for i in moving]
        sensed = min(max(needed, default=0.0) + act0.margin, act0.relief)
        if compensated:
            available = pump.available(sensed)
            share = available / total if total > available else 1.0
            return [speed * share for speed, _ in demands]
        curves = [act.supplied_at(area, s) for act, area, s in zip(actuators, areas, extensions)]
        flows = _passed(actuators, curves, demands, sensed)
        if sum(flow for _, flow in flows) <= pump.available(sensed):
            return [speed for speed, _ in flows]
        low, high = 0.0, sensed
        for _ in range(STEPS):
            middle = 0.5 * (low + high)
            passed = sum(flow for _, flow in _passed(actuators, curves, demands, middle))
            if passed > pump.available(middle):
                high = middle
            else:
                low = middle
        return [speed for speed, _ in _passed(actuators, curves, demands, low)]

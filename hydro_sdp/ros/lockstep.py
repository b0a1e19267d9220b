"""
Lockstep: a plant node advanced one period at a time until the graph has settled.

Reasoning: methods 9.4.

"""

from __future__ import annotations

from typing import Callable, Iterable, Protocol


class SteppingHarness(Protocol):
    """What Lockstep needs of the harness (:class:`hydro_sdp.ros.testing.RosHarness`)."""

    def set_time(self, nanoseconds: int) -> None:
        """Set the clock of every simulated-time node."""

    def spin_until(self, predicate: Callable[[], bool], timeout: float = 5.0) -> bool:
        """Spin until ``predicate()`` holds or ``timeout`` s pass; return whether it held."""


class Observer(Protocol):
    """A node that counts the samples and commands it took (an identifier, a recorder)."""

    @property
    def samples(self) -> int:
        """Joint-state samples taken so far."""

    @property
    def commands_received(self) -> int:
        """Valve commands taken so far."""


class SteppedPlant(Protocol):
    """A plant node the harness steps: its period, its ticks, its commands and subscribers."""

    @property
    def sample_period(self) -> float:
        """Plant period, s."""

    @property
    def ticks(self) -> int:
        """Periods simulated so far."""

    @property
    def commands_received(self) -> int:
        """Valve commands taken so far."""

    def count_subscribers(self, topic_name: str) -> int:
        """Return the number of subscribers to ``topic_name``."""


class LoopController(Protocol):
    """A controller node in a lockstep loop: its counters and its command publishers."""

    @property
    def joint(self) -> str:
        """Return the (first) joint it controls."""

    @property
    def samples(self) -> int:
        """Joint-state samples taken so far."""

    @property
    def outputs(self) -> int:
        """Valve commands published so far."""

    def count_subscribers(self, topic_name: str) -> int:
        """Return the number of subscribers to ``topic_name``."""


class Lockstep:
    """
    Advance a plant node one period at a time and wait until the graph has settled.

    ``observers``: nodes with ``samples`` (and ``commands_received``) counters, e.g. identifiers.
    ``timeout``: wall-clock limit of one step, s.
    """

    def __init__(self, harness: SteppingHarness, plant: SteppedPlant, *,
                 controllers: Iterable[LoopController] = (), observers: Iterable[Observer] = (),
                 timeout: float = 5.0) -> None:
        self.harness = harness
        self.plant = plant
        self.controllers = list(controllers)
        self.observers = list(observers)
        self.period_ns = int(round(plant.sample_period * 1e9))
        self.timeout = timeout
        self.steps = 0
        listeners = len(self.controllers) + len(self.observers)
        matched = harness.spin_until(lambda: plant.count_subscribers('joint_states') >= listeners
                                     and all(c.count_subscribers(f'{joint}/valve_command') >= 1
                                             for c in self.controllers
                                             for joint in getattr(c, 'joints', [c.joint])),
                                     timeout)
        if not matched:
            raise TimeoutError('the nodes did not discover each other')

    def _settled(self) -> bool:
        ticks = self.plant.ticks
        if ticks != self.steps:
            return False
        outputs = sum(controller.outputs for controller in self.controllers)
        if any(controller.samples != ticks for controller in self.controllers):
            return False
        if self.controllers and self.plant.commands_received < outputs:
            return False
        for observer in self.observers:
            if observer.samples != ticks:
                return False
            if self.controllers and observer.commands_received < outputs:
                return False
        return True

    def step(self) -> None:
        """Advance one plant period and wait for the graph to settle."""
        self.steps += 1
        self.harness.set_time(self.steps * self.period_ns)
        if not self.harness.spin_until(self._settled, self.timeout):
            raise TimeoutError(f'lockstep step {self.steps} did not settle (plant ticks '
                               f'{self.plant.ticks})')

    def run(self, steps: int, on_step: Callable[[int], None] | None = None) -> None:
        """Advance ``steps`` periods, calling ``on_step(k)`` after each."""
        for _ in range(steps):
            self.step()
            if on_step is not None:
                on_step(self.steps)

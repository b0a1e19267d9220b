"""
Several joints of the physics plant driven at once by random duties held for random times.

Each joint in ``moving`` has its own levels and hold times; the sign of each new
level heads away from the nearer stop more often than not, so the joints turn
back before their stops. (``hydro_sdp.core.synthetic.physics.runs.random_levels``
drives one joint and returns its record; these runs drive several together, as on
a machine whose joints share a pump.)

"""

from __future__ import annotations

from typing import Sequence

from hydro_sdp.core.synthetic.physics.linkage import Geometry
from hydro_sdp.core.synthetic.physics.machine import PlantSimulator
from hydro_sdp.core.synthetic.physics.plant import Machine
from hydro_sdp.core.synthetic.physics.runs import duty_command
import numpy as np

#: Range of the duty magnitudes, percent, and of the hold times, s.
DUTIES = (35.0, 100.0)
HOLDS = (0.5, 3.0)


def plant_levels(machine: Machine, dt: float, duration: float, moving: Sequence[int],
                 seed: int, *, resting: int = 1) -> tuple[np.ndarray, np.ndarray]:
    """
    Drive the joints in ``moving`` with random duties held 0.5-3 s, turning before stops.

    Parameters
    ----------
    machine : Machine
        The plant; every joint starts at rest in the middle of its travel.
    dt : float
        Sample period, s.
    duration : float
        Length of the run, s.
    moving : sequence of int
        The joints driven; the others stay at neutral.
    seed : int
        Seed of the levels, the holds and the sensor noise.
    resting : int
        Samples at neutral before the first level (the first is the initial state).

    Returns
    -------
    tuple
        ``(commands, angles)``: one row a sample, one column a joint.

    """
    rng = np.random.default_rng(seed)
    neutral = [joint.valve.neutral for joint in machine.joints]
    limits = [Geometry(joint).angle_limits for joint in machine.joints]
    sim = PlantSimulator(machine, dt, angles0=[0.5 * (low + high) for low, high in limits],
                         command_before=neutral, seed=seed)
    commands, angles = [list(neutral)], [sim.angles]
    for _ in range(resting - 1):
        commands.append(list(neutral))
        angles.append(sim.step(neutral))
    current, left = list(neutral), [0] * len(neutral)
    while len(commands) < int(round(duration / dt)):
        for j in moving:
            if left[j] <= 0:
                low, high = limits[j]
                sign = 1.0 if rng.random() > (angles[-1][j] - low) / (high - low) else -1.0
                current[j] = duty_command(machine, j, sign * rng.uniform(*DUTIES))
                left[j] = int(round(rng.uniform(*HOLDS) / dt))
            left[j] -= 1
        commands.append(list(current))
        angles.append(sim.step(current))
    return np.array(commands), np.array(angles)

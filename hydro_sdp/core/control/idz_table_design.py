"""
The map's own inverse as the IDZ of a model: the table, its command range and its band.

See methods 5.4-5.5.
"""

from __future__ import annotations


from hydro_sdp.core.control.idz import IdzMode
from hydro_sdp.core.control.idz_table import TableInverseDeadZone
from hydro_sdp.core.control.loop_noise import noise_gain
from hydro_sdp.core.control.pip_design import DiscretePlant, PipGains
from hydro_sdp.core.errors import DataError
from hydro_sdp.core.model.command_span import command_span
from hydro_sdp.core.model.joint_model import JointModel
from hydro_sdp.core.model.timing import SamplePeriod
import numpy as np

#: Angle the smallest correction of [W18]'s J2 loop moves: its band 0.05 deg per sample
#: for its 3 samples of delay; a table's default band keeps it for the model's own dynamics.
SMALLEST_CORRECTION = 0.15
#: A table's band is at least this many standard deviations of the noise on ``u``.
NOISE_MULTIPLE = 3.0
#: Angle noise a design assumes when none is given, deg (the identifier's default).
DEFAULT_NOISE = 0.03
#: Points of each branch of an IDZ table.
TABLE_POINTS = 40


def table_beta(dead_zone: tuple[float, float], plant: DiscretePlant, gains: PipGains,
               lag: float | None, control_period: SamplePeriod, noise_std: float) -> float:
    """Return the default chatter band of an IDZ table, degrees per control sample."""
    if dead_zone[1] <= dead_zone[0]:
        return 0.0
    samples = plant.delay + (0.0 if lag is None else lag / control_period)
    noise = NOISE_MULTIPLE * noise_std * noise_gain(plant, gains) if noise_std > 0.0 else 0.0
    return max(SMALLEST_CORRECTION / samples, noise)


def _branch(model: JointModel, rest: float, end: float,
            control_period: SamplePeriod) -> tuple[list[float], list[float]]:
    """Return one branch of the table, ``(u, v)`` from the edge outward (u from 0)."""
    sign = 1.0 if end > rest else -1.0
    dead_zone = model.dead_zone
    edge = rest
    if dead_zone is not None:
        edge = min(max(dead_zone[1] if sign > 0 else dead_zone[0], min(rest, end)),
                   max(rest, end))
    v = np.linspace(edge, end, 4001)
    u = np.clip(sign * control_period * model.rate(v), 0.0, None)
    # A valve's speed does not grow towards rest: where a fitted map (a poly's extrapolation
    # inside the commands the runs held) stops and moves again nearer rest, the joint is
    # taken as still from where the speed first reaches 0 coming in from the end.
    u = np.minimum.accumulate(u[::-1])[::-1]
    moving = np.flatnonzero(u > 0.0)
    if not moving.size:
        raise DataError(f'the {model.kind} map does not move the joint '
                        f'{"down" if sign < 0 else "up"} within the commands '
                        f'{sorted([rest, end])}')
    start = max(int(moving[0]) - 1, 0)
    v, u = v[start:], u[start:]
    keep = np.r_[True, np.diff(u) > 0.0]     # a flat stretch: its first command
    v, u = v[keep], u[keep]
    # Points of the map evenly spaced along the curve drawn on the unit square (steep and
    # flat parts alike), the first (the edge) and the last (the end) always among them.
    step = np.hypot(np.diff(u) / u[-1], np.diff(v) / (v[-1] - v[0]))
    length = np.r_[0.0, np.cumsum(step)]
    chosen = np.unique(np.r_[0, np.searchsorted(length, np.linspace(
        0.0, length[-1], TABLE_POINTS)[1:-1]), u.size - 1])
    u_table, v_table = u[chosen], v[chosen]
    u_table[0] = 0.0
    keep = np.r_[True, np.diff(u_table) > 0.0]
    return (sign * u_table[keep] + 0.0).tolist(), v_table[keep].tolist()   # no -0.0


def table_idz(model: JointModel, control_period: SamplePeriod, *, beta: float,
              mode: IdzMode = 'zero',
              v_range: tuple[float, float] | None = None) -> TableInverseDeadZone:
    """Return the map's own inverse as the IDZ table at the control period (methods.md 5.4)."""
    low, high = command_span(model, v_range)
    rest = model.rest_command
    negative_u, negative_v = _branch(model, rest, low, control_period)
    positive = _branch(model, rest, high, control_period)
    return TableInverseDeadZone.from_branches(
        (negative_u[::-1], negative_v[::-1]), positive, beta=beta, mode=mode, rest=rest)

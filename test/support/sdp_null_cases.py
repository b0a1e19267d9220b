"""
Joints with nothing left for the SDP analysis to find: the calibration of its test.

Each case is a true joint of the independent generator (:mod:`support.joint_generator`,
through the grid's random joints of :mod:`support.diagnosis_grid`) and records of it:

* ``ratio``: the analysis is given the true joint's own model file, so neither the
  ratio of the measured to the modelled increment nor the increment residual depends
  on any state; every state/direction pair it tests is a null;
* ``arx``: no model; the joint has no lag and no factor of the angle, so the SDP-ARX
  gain depends on the command alone and every pair of another state is a null.

The joints vary as the grid's do (dead-zones, speeds, delays, stops); the records in
volts, percent resting at 50 or signed percent, driven by random levels, full strokes
(pushed against the stops) or steps from rest and back, with a second joint moving
on its own and a measured load the joint does not feel (``others_speed`` and ``load``
are nulls too), at sensor noise from 0.005 to 0.08 deg; with ``drift``, the joint's
speed wanders by a slow random factor the model does not have (residuals correlated
over seconds, no state to explain them).

"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Sequence

from hydro_sdp.core.arrays import FloatArray
from hydro_sdp.core.model.joint_model import JointModel
from hydro_sdp.core.model.records import Record
import numpy as np
from support.diagnosis_grid import hide, UNITS
from support.grid_programs import load_signal, other_levels, program as grid_program
from support.joint_generator import Joint, record, SpeedMap

#: Programs of the cases.
PROGRAMS = ('random', 'stroke', 'steps')
#: The words whose true joint a ``ratio`` case is given the model of (its effects included).
RATIO_WORDS = ('none', 'valve_lag', 'direction_dependent_delay')
#: An independent joint on another pump: its speed is a state the joint does not feel.
OTHER = Joint(SpeedMap('exp', (-1.0, 1.0), (30.0, 30.0), (0.8, 0.8)), delay=0.1,
              stops=(-40.0, 40.0))
DT = 0.01


@dataclass(frozen=True, eq=False)
class NullCase:
    """A null case: its records and the model the analysis is given (None: ``arx``)."""

    target: str
    word: str
    program: str
    units: str
    noise: float
    drift: float
    records: tuple[Record, ...]
    model: JointModel | None

    @property
    def name(self) -> str:
        """Return a short description."""
        drift = f' drift {self.drift:g}' if self.drift else ''
        return f'{self.target} {self.word} {self.program} {self.units} {self.noise:g}{drift}'


def steps_program(truth: JointModel, rng: np.random.Generator, seconds: float) -> FloatArray:
    """
    Return steps from rest and back: a level held 1-2.5 s, rest, often the same level back.

    Each step is cut short 10 % of the stroke before a stop, as a careful experimenter runs
    them; levels from the dead-zone's edge to 90 % of the command range.
    """
    assert truth.angle_limits is not None and truth.dead_zone is not None
    assert truth.input_limits is not None
    low, high = truth.angle_limits
    margin = 0.1 * (high - low)
    rest = truth.rest_command
    total = int(round(seconds / DT))
    pieces = [np.full(int(round(float(rng.uniform(0.5, 1.5)) / DT)), rest)]
    y = 0.5 * (low + high)
    while sum(p.size for p in pieces) < total:
        sign = 1.0 if y < 0.5 * (low + high) else -1.0
        side = int(sign > 0)
        edge, end = truth.dead_zone[side], truth.input_limits[side]
        level = edge + float(rng.uniform(0.05, 0.9)) * (end - edge)
        for direction in ((1.0, -1.0) if rng.random() < 0.6 else (1.0,)):
            command = level if direction > 0 else rest - (level - rest)
            speed = float(truth.rate(command))
            room = (high - margin - y) if speed > 0 else (y - low - margin)
            hold = min(float(rng.uniform(1.0, 2.5)), max(room, 0.0) / max(abs(speed), 1e-6))
            samples = max(1, int(round(hold / DT)))
            y += speed * samples * DT
            pieces += [np.full(samples, command),
                       np.full(int(round(float(rng.uniform(0.5, 1.5)) / DT)), rest)]
    return np.concatenate(pieces)[:total]


def slow_factor(rng: np.random.Generator, n: int, size: float) -> FloatArray:
    """Return ``1 + e(t)``: ``e`` a Gauss-Markov process of std ``size``, correlated over 1-4 s."""
    pole = float(np.exp(-DT / rng.uniform(1.0, 4.0)))
    steps = rng.normal(0.0, size * np.sqrt(1.0 - pole * pole), n)
    e = np.empty(n)
    e[0] = rng.normal(0.0, size)
    for k in range(1, n):
        e[k] = pole * e[k - 1] + steps[k]
    return 1.0 + e


def null_case(target: str, program: str, seed: int, *, word: str = 'none',
              drift: float = 0.0, units: str | None = None, noise: float | None = None,
              seconds: float = 40.0, count: int = 2) -> NullCase:
    """
    Return one null case.

    Parameters
    ----------
    target : str
        ``ratio`` (the true model given) or ``arx`` (no model; a joint without lag).
    program : str
        One of :data:`PROGRAMS`.
    seed : int
        Seed of every draw.
    word : str
        ``ratio``: the grid word whose true joint is drawn (its effect in the model too).
    drift : float
        Standard deviation of a slow random factor on the joint's speed that no state
        explains and the model does not have (:func:`slow_factor`; 0: none): residuals
        correlated over seconds, as a model wrong elsewhere leaves them.
    units : str or None
        Key of :data:`support.diagnosis_grid.UNITS`; default: by the seed.
    noise : float or None
        Angle noise, deg; default by the seed and the program: 0.005, 0.02 or 0.08.
    seconds : float
        Length of each record, s.
    count : int
        Records.

    Returns
    -------
    NullCase
        The case.

    """
    units = units or list(UNITS)[seed % len(UNITS)]
    noise = noise if noise is not None else (0.005, 0.02, 0.08)[
        (seed + PROGRAMS.index(program)) % 3]
    rng = np.random.default_rng([seed, PROGRAMS.index(program), 41 if target == 'arx' else 43,
                                 RATIO_WORDS.index(word), int(drift > 0.0)])
    truth, _ = hide(word if target == 'ratio' else 'none', rng, units)
    joint = replace(truth.joint, noise=noise)
    if drift > 0.0:
        # The generator's load factor carries the slow factor; the record gets no load.
        joint = replace(joint, load_factor=lambda factor, direction: factor)
    truth = replace(truth, joint=joint, other=OTHER if seed % 2 == 0 else None)
    machine = replace(truth.machine, dt=DT)
    model = truth.model
    assert model.angle_limits is not None
    made = []
    for index in range(count):
        if program == 'steps':
            v, y0 = steps_program(model, rng, seconds), 0.5 * sum(model.angle_limits)
        else:
            v, y0 = grid_program(model, program, rng, seconds, DT)
        commands = v[:, None] if truth.other is None else np.column_stack(
            [v, other_levels(rng, v.size, DT)])
        factor = slow_factor(rng, v.size, drift) if drift > 0.0 else None
        made.append(record(machine, commands, angles0=[y0, 0.0][:commands.shape[1]],
                           load=factor, seed=int(rng.integers(1 << 30)),
                           source=f'null {seed} #{index}'))
        # A measured load the joint does not feel, in half the cases.
        felt = load_signal(rng, v.size, DT, float(rng.uniform(10.0, 120.0)))
        made[-1] = replace(made[-1], load=felt if seed % 4 < 2 else None)
    return NullCase(target, word if target == 'ratio' else 'none', program, units, noise,
                    drift, tuple(made), model if target == 'ratio' else None)


def null_pairs(analysis: object, target: str) -> list[tuple[str, str, str, float]]:
    """
    Return the tested state/direction pairs that are nulls: ``(parameter, state, direction, p)``.

    ``ratio``: every tested pair; ``arx``: the pairs of states other than the command.
    """
    entries: Sequence = tuple(analysis.states) + tuple(analysis.residual)  # type: ignore
    return [(e.parameter, e.state, e.direction, float(e.p_value)) for e in entries
            if np.isfinite(e.p_value) and (target == 'ratio' or e.state != 'command')]

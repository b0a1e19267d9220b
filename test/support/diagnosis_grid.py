"""
A grid of simulated joints to check the discrepancy workflow on (docs/methods.md section 8.7).

Each case is a true joint, a nominal model that misses one word of the
vocabulary (or nothing: ``none``), and records of the true joint driven by one
of two programs: random levels kept inside the end stops, or full-stroke runs
from stop to stop. The joints differ from J2 on purpose: dead-zones from narrow
to wide, slow and fast, delays of 0.03-0.3 s, commands in volts (+-10), in
percent resting at 50 (0..100) or in signed percent (-100..100).

"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Sequence

from hydro_sdp.core.arrays import FloatArray
from hydro_sdp.core.diagnosis.search import diagnose
from hydro_sdp.core.model.effects import (
    AngleDependentVelocity, Backlash, DirectionDependentDelay, StrokeGeometry, ValveLag)
from hydro_sdp.core.model.joint_model import JointModel
from hydro_sdp.core.model.records import Record
from hydro_sdp.core.model.simulation import simulate
from hydro_sdp.core.model.static_maps import linearise, LinearMap, SdpDzMap, SdpMap, StaticMap
import numpy as np

#: Input units of the grid: name, command range, rest command.
UNITS: dict[str, tuple[tuple[float, float], float]] = {
    'volt': ((-10.0, 10.0), 0.0),
    'percent': ((0.0, 100.0), 50.0),
    'signed_percent': ((-100.0, 100.0), 0.0),
}

#: The words hidden in turn, and ``none`` (nothing missing); each case is seeded by its
#: word's place here.
WORDS: tuple[str, ...] = (
    'dead_zone', 'velocity_saturation', 'asymmetry', 'time_delay',
    'direction_dependent_delay', 'angle_limits', 'valve_lag', 'backlash',
    'angle_dependent_velocity', 'none', 'stroke_geometry')

#: The two programs.
PROGRAMS: tuple[str, ...] = ('random', 'stroke')


@dataclass(frozen=True, eq=False)
class GridCase:
    """
    One case of the grid.

    Parameters
    ----------
    word : str
        The word the nominal model misses (``none``: nothing).
    program : str
        ``random`` (levels inside the stops) or ``stroke`` (stop to stop).
    units : str
        Key of :data:`UNITS`.
    truth, model : JointModel
        The true joint and the nominal model.
    estimation, validation : tuple of Record
        Records of the true joint.

    """

    word: str
    program: str
    units: str
    truth: JointModel
    model: JointModel
    estimation: tuple[Record, ...]
    validation: tuple[Record, ...]


@dataclass(frozen=True)
class GridResult:
    """
    What the workflow named for one case.

    Parameters
    ----------
    word, program, units : str
        The case.
    named : str
        The first word named.
    mae_before, mae_after : float
        Validation MAE of the nominal and of the final model, degrees.

    """

    word: str
    program: str
    units: str
    named: str
    mae_before: float
    mae_after: float

    @property
    def right(self) -> bool:
        """Whether the right word came first and (when one is missing) the gap halved."""
        if self.word == 'none':
            return self.named == 'none'
        return self.named == self.word and self.mae_after <= 0.5 * self.mae_before


def _joint(rng: np.random.Generator, units: str) -> JointModel:
    """Return a random true joint in ``units``: sdp map, asymmetric, with end stops."""
    (low, high), rest = UNITS[units]
    half = min(rest - low, high - rest)
    width = float(rng.uniform(0.03, 0.25)) * half
    edges = (rest - width * float(rng.uniform(0.7, 1.3)),
             rest + width * float(rng.uniform(0.7, 1.3)))
    speed = float(rng.uniform(10.0, 70.0))
    # The speed saturates within the command range: 95 % at 40-90 % of the span.
    reach = [(half - width) * float(r) for r in rng.uniform(0.4, 0.9, 2)]
    curvature = (3.0 / reach[0], 3.0 / reach[1])
    static_map = SdpMap(edges, (-speed * float(rng.uniform(0.7, 1.0)),
                                speed * float(rng.uniform(0.9, 1.3))), curvature)
    bottom = float(rng.uniform(-60.0, 10.0))
    return JointModel('joint', static_map, delay=round(float(rng.uniform(0.03, 0.3)), 2),
                      angle_limits=(bottom, bottom + float(rng.uniform(50.0, 120.0))),
                      input_limits=(low, high))


def _symmetric(static_map: SdpMap, rest: float) -> SdpMap:
    edge = 0.5 * (static_map.dead_zone[1] - static_map.dead_zone[0])
    speed = 0.5 * (static_map.saturation_velocity[1] - static_map.saturation_velocity[0])
    curvature = 0.5 * (static_map.curvature[0] + static_map.curvature[1])
    return SdpMap((rest - edge, rest + edge), (-speed, speed), (curvature, curvature))


def _without_dead_zone(static_map: SdpDzMap, rest: float) -> StaticMap:
    slope = static_map.slope[1]
    if rest == 0.0:
        return LinearMap(slope)
    # A linear map turns about 0; about another rest it is an sdp_dz map with no width.
    return SdpDzMap((rest, rest), (slope, slope))


def hide(word: str, rng: np.random.Generator, units: str) -> tuple[JointModel, JointModel]:
    """
    Return a true joint and a nominal model that misses ``word``.

    Parameters
    ----------
    word : str
        One of :data:`WORDS`.
    rng : numpy.random.Generator
        Random draws.
    units : str
        Key of :data:`UNITS`.

    Returns
    -------
    tuple[JointModel, JointModel]
        ``(truth, model)``.

    """
    truth = _joint(rng, units)
    rest = UNITS[units][1]
    static_map = truth.static_map
    assert isinstance(static_map, SdpMap)
    span = (static_map.dead_zone[0] - 2.0 / static_map.curvature[0],
            static_map.dead_zone[1] + 2.0 / static_map.curvature[1])
    if word == 'dead_zone':
        # A linear nominal model (or one with no width about the rest) of a dead-zone joint
        # whose sides have one slope (a linear model cannot tell the sides apart either).
        chords = linearise(static_map, *span)
        chords = replace(chords, slope=(chords.slope[1], chords.slope[1]))
        return replace(truth, static_map=chords), replace(
            truth, static_map=_without_dead_zone(chords, rest))
    if word == 'velocity_saturation':
        return truth, replace(truth, static_map=linearise(static_map, *span))
    if word == 'asymmetry':
        return truth, replace(truth, static_map=_symmetric(static_map, rest))
    if word == 'time_delay':
        shift = max(0.03, 0.5 * truth.delay) * float(rng.choice([-1.0, 1.0]))
        wrong = round(truth.delay + shift, 2) if truth.delay + shift >= 0.01 else \
            round(truth.delay + abs(shift), 2)
        return truth, replace(truth, delay=wrong)
    if word == 'direction_dependent_delay':
        later = truth.delay + max(0.05, float(rng.uniform(0.4, 0.8)) * truth.delay)
        slower = round(min(later, 0.45), 2)
        split = (truth.delay, slower) if rng.random() < 0.5 else (slower, truth.delay)
        return truth.with_effect(DirectionDependentDelay(*split)), truth
    if word == 'angle_limits':
        return truth, replace(truth, angle_limits=None)
    if word == 'valve_lag':
        return truth.with_effect(ValveLag(float(rng.uniform(0.05, 0.3)))), truth
    if word == 'backlash':
        return truth.with_effect(Backlash(float(rng.uniform(1.0, 3.0)))), truth
    if word == 'angle_dependent_velocity':
        return truth.with_effect(AngleDependentVelocity(float(rng.uniform(0.2, 0.4)),
                                                        float(rng.uniform(0.0, 360.0)))), truth
    if word == 'stroke_geometry':
        return truth.with_effect(stroke_geometry(rng, truth)), truth
    return truth, truth


def stroke_geometry(rng: np.random.Generator, truth: JointModel) -> StrokeGeometry:
    """
    Return a linkage factor over the stroke of ``truth``, the same for both directions.

    Smooth (a random cosine and a slope over five knots), the fastest part of the
    stroke x1.4-2 the slowest, with cushions over 5 % of the stroke at each end.
    """
    assert truth.angle_limits is not None
    low, high = truth.angle_limits
    share = np.linspace(0.0, 1.0, 5)
    shape = np.cos(np.pi * share + float(rng.uniform(0.0, np.pi))) + \
        float(rng.uniform(-1.0, 1.0)) * share
    shape = (shape - shape.min()) / np.ptp(shape)
    factors = np.exp(np.log(float(rng.uniform(1.4, 2.0))) * (shape - 0.5))
    return StrokeGeometry(tuple(low + (high - low) * share), tuple(factors.tolist()),
                          cushion=0.05 * (high - low),
                          cushion_factor=float(rng.uniform(0.3, 0.6)))


def _levels(rng: np.random.Generator, truth: JointModel, sign: float,
            smallest: float) -> float:
    """Return a command driving ``truth`` towards ``sign`` at a random share of its range."""
    static_map = truth.static_map
    assert static_map.dead_zone is not None and truth.input_limits is not None
    side = 1 if sign > 0 else 0
    edge = static_map.dead_zone[side]
    end = truth.input_limits[side]
    return edge + rng.uniform(smallest, 0.9) * (end - edge)


def program(truth: JointModel, kind: str, rng: np.random.Generator, seconds: float,
            dt: float) -> tuple[FloatArray, float]:
    """
    Return commands for ``truth`` and the angle to start from.

    ``random``: random levels (dead-zone included) held 0.5-3 s, cut short before the
    joint would leave the middle 80 % of its stroke. ``stroke``: runs at a random level
    from one stop to the other, pushed against the stop for 0.3-1.5 s, some rests.

    Parameters
    ----------
    truth : JointModel
        The true joint (its stops and map shape the program).
    kind : str
        ``random`` or ``stroke``.
    rng : numpy.random.Generator
        Random draws.
    seconds : float
        Length, s.
    dt : float
        Sample period, s.

    Returns
    -------
    tuple[FloatArray, float]
        Commands and the start angle, degrees.

    """
    assert truth.angle_limits is not None and truth.dead_zone is not None
    low, high = truth.angle_limits
    rest = truth.rest_command
    total = int(round(seconds / dt))
    pieces: list[FloatArray] = []
    filled = 0
    y = 0.5 * (low + high)
    margin = 0.1 * (high - low)
    while filled < total:
        if kind == 'random':
            up = rng.random() < min(max((high - margin - y) / (high - low - 2 * margin),
                                        0.1), 0.9)
            sign = 1.0 if up else -1.0
            level = _levels(rng, truth, sign, -0.3)
            if (level - rest) * sign < 0.0:
                level = rest
            speed = float(truth.rate(level))
            hold = rng.uniform(0.5, 3.0)
            if speed != 0.0:
                room = (high - margin - y) if speed > 0 else (y - low - margin)
                hold = min(hold, max(room, 0.0) / abs(speed))
            samples = max(1, int(round(hold / dt)))
            y += speed * samples * dt
            pieces.append(np.full(samples, level))
        else:
            sign = 1.0 if y < 0.5 * (low + high) else -1.0
            level = _levels(rng, truth, sign, 0.3)
            speed = abs(float(truth.rate(level)))
            travel = (high - y) if sign > 0 else (y - low)
            hold = travel / max(speed, 1e-6) + rng.uniform(0.3, 1.5)
            samples = int(round(hold / dt))
            pieces.append(np.full(samples, level))
            y = high if sign > 0 else low
            if rng.random() < 0.5:
                pieces.append(np.full(int(round(rng.uniform(0.3, 1.5) / dt)), rest))
        filled = sum(p.size for p in pieces)
    return np.concatenate(pieces)[:total], 0.5 * (low + high)


def make_case(word: str, kind: str, units: str, seed: int, *, seconds: float = 60.0,
              dt: float = 0.01, noise: float = 0.02) -> GridCase:
    """
    Return one case: joint, nominal model, two estimation records and one validation record.

    Parameters
    ----------
    word : str
        One of :data:`WORDS`.
    kind : str
        One of :data:`PROGRAMS`.
    units : str
        Key of :data:`UNITS`.
    seed : int
        Seed of the draws.
    seconds : float
        Length of each record, s.
    dt : float
        Sample period, s.
    noise : float
        Standard deviation of the angle noise, degrees.

    Returns
    -------
    GridCase
        The case.

    """
    rng = np.random.default_rng([seed, WORDS.index(word), PROGRAMS.index(kind),
                                 list(UNITS).index(units)])
    truth, model = hide(word, rng, units)
    records = []
    for _ in range(3):
        v, y0 = program(truth, kind, rng, seconds, dt)
        y = simulate(truth, v, dt, y0, v_before=float(v[0])) + rng.normal(0.0, noise, v.size)
        records.append(Record(np.arange(1, v.size + 1) * dt, v, y, joint=truth.joint))
    return GridCase(word, kind, units, truth, model, tuple(records[:2]), (records[2],))


def run_case(case: GridCase) -> GridResult:
    """Diagnose one case and return what was named."""
    result = diagnose(case.estimation, case.model, validation=case.validation)
    return GridResult(case.word, case.program, case.units, result.effect, result.mae_before,
                      result.mae_after)


def confusion_table(results: Sequence[GridResult]) -> list[str]:
    """
    Return the confusion table as Markdown rows: hidden word against first word named.

    Parameters
    ----------
    results : sequence of GridResult
        Grid results.

    Returns
    -------
    list[str]
        Header, one row per hidden word (with the share right, gap halved), a total.

    """
    hidden = [w for w in WORDS if any(r.word == w for r in results)]
    named = list(dict.fromkeys([*hidden, *sorted({r.named for r in results} - set(hidden))]))
    short = {w: w.replace('direction_dependent_delay', 'dir_delay')
             .replace('angle_dependent_velocity', 'angle_vel')
             .replace('velocity_saturation', 'saturation') for w in named}
    rows = ['| hidden \\ named | ' + ' | '.join(short[w] for w in named) + ' | right |',
            '|---' * (len(named) + 2) + '|']
    for word in hidden:
        mine = [r for r in results if r.word == word]
        counts = [sum(r.named == w for r in mine) for w in named]
        right = sum(r.right for r in mine)
        rows.append(f'| {short.get(word, word)} | ' + ' | '.join(str(c) for c in counts)
                    + f' | {right}/{len(mine)} |')
    right = sum(r.right for r in results)
    rows.append(f'| all | {" | ".join("" for _ in named)} | {right}/{len(results)} |')
    return rows

"""
A grid of joints to check the discrepancy workflow on (docs/methods.md section 8.7).

Each case is a true joint simulated by the independent generator
(:mod:`support.joint_generator`: its own maps, lags, integrator and effects), a
nominal model that misses one word of the vocabulary (or nothing: ``none``) written
from the same numbers through the model file's documented keys, and records of the
true joint driven by one of two programs: random levels kept inside the end stops, or
full-stroke runs from stop to stop. The joints differ from J2 on purpose: dead-zones
from narrow to wide, slow and fast, delays of 0.03-0.3 s, commands in volts (+-10),
in percent resting at 50 (0..100) or in signed percent (-100..100). For
``flow_sharing`` a second joint on the same pump moves at random; for
``load_dependence`` each record carries a measured load (a payload of its own and a
digging force that comes and goes) that slows the joint through a valve without
pressure compensation; for ``oscillation`` the link rings on the oil column (a mode
of 1.5-4 Hz, damping ratio 0.05-0.2).

"""

from __future__ import annotations

from dataclasses import dataclass, replace
import math
from typing import Any, Sequence

from hydro_sdp.core.diagnosis.search import diagnose
from hydro_sdp.core.model.joint_model import JointModel
from hydro_sdp.core.model.records import Record
import numpy as np
from support.grid_programs import load_signal, other_levels, program
from support.grid_results import GridResult
from support.joint_generator import Joint, Machine, record, SpeedMap, Stroke

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
    'angle_dependent_velocity', 'none', 'stroke_geometry', 'flow_sharing', 'load_dependence',
    'oscillation')

#: The two programs.
PROGRAMS: tuple[str, ...] = ('random', 'stroke')


@dataclass(frozen=True)
class Truth:
    """
    A true joint: the numbers of its model file and what the generator adds to them.

    Parameters
    ----------
    mapping : dict
        Its model file (docs/interfaces.md section 1), the documented keys.
    joint : Joint
        The generator's joint with the same numbers.
    other : Joint or None
        The other joint on the pump.

    """

    mapping: dict[str, Any]
    joint: Joint
    other: Joint | None = None

    @property
    def model(self) -> JointModel:
        """Return the true joint's model, read from its model file."""
        return JointModel.from_mapping(self.mapping)

    @property
    def machine(self) -> Machine:
        """Return the generator's machine."""
        joints = (self.joint,) if self.other is None else (self.joint, self.other)
        return Machine(joints)


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
    truth : Truth
        The true joint.
    model : JointModel
        The nominal model.
    estimation, validation : tuple of Record
        Records of the true joint.

    """

    word: str
    program: str
    units: str
    truth: Truth
    model: JointModel
    estimation: tuple[Record, ...]
    validation: tuple[Record, ...]


def _base(rng: np.random.Generator, units: str) -> dict[str, Any]:
    """Return a random true joint's model file in ``units``: sdp map, asymmetric, stops."""
    (low, high), rest = UNITS[units]
    half = min(rest - low, high - rest)
    width = float(rng.uniform(0.03, 0.25)) * half
    edges = [rest - width * float(rng.uniform(0.7, 1.3)),
             rest + width * float(rng.uniform(0.7, 1.3))]
    speed = float(rng.uniform(10.0, 70.0))
    # The speed saturates within the command range: 95 % at 40-90 % of the span.
    reach = [(half - width) * float(r) for r in rng.uniform(0.4, 0.9, 2)]
    bottom = float(rng.uniform(-60.0, 10.0))
    return {'format': 'hydro_sdp/model/v1', 'joint': 'joint', 'kind': 'sdp',
            'delay': round(float(rng.uniform(0.03, 0.3)), 2),
            'angle_limits': [bottom, bottom + float(rng.uniform(50.0, 120.0))],
            'input_limits': [low, high], 'dead_zone': edges,
            'saturation_velocity': [-speed * float(rng.uniform(0.7, 1.0)),
                                    speed * float(rng.uniform(0.9, 1.3))],
            'curvature': [3.0 / reach[0], 3.0 / reach[1]], 'effects': {}}


def _speed_map(mapping: dict[str, Any]) -> SpeedMap:
    """Return the generator's map with the numbers of a model file's ``sdp`` or ``sdp_dz`` map."""
    edges = tuple(mapping['dead_zone'])
    if mapping['kind'] == 'sdp_dz':
        return SpeedMap('linear', edges, rise=tuple(mapping['slope']))
    low, high = mapping['saturation_velocity']
    return SpeedMap('exp', edges, (-low, high), tuple(mapping['curvature']))


def _chords(mapping: dict[str, Any], equal: bool) -> dict[str, Any]:
    """Return an ``sdp_dz`` map through the sdp map's two-thirds-of-saturation points."""
    low, high = mapping['dead_zone']
    vn, vp = mapping['saturation_velocity']
    cn, cp = mapping['curvature']
    # rate = V (1 - exp(-c u)) reaches 2/3 V at u = ln(3) / c: slope (2/3 V) / u.
    slopes = [2.0 / 3.0 * -vn * cn / math.log(3.0), 2.0 / 3.0 * vp * cp / math.log(3.0)]
    if equal:
        slopes = [slopes[1], slopes[1]]
    out = {k: v for k, v in mapping.items()
           if k not in ('saturation_velocity', 'curvature')}
    return {**out, 'kind': 'sdp_dz', 'dead_zone': [low, high], 'slope': slopes}


def _symmetric(mapping: dict[str, Any], rest: float) -> dict[str, Any]:
    low, high = mapping['dead_zone']
    edge = 0.5 * (high - low)
    vn, vp = mapping['saturation_velocity']
    cn, cp = mapping['curvature']
    speed, curvature = 0.5 * (vp - vn), 0.5 * (cn + cp)
    return {**mapping, 'dead_zone': [rest - edge, rest + edge],
            'saturation_velocity': [-speed, speed], 'curvature': [curvature, curvature]}


def _stroke(rng: np.random.Generator, limits: Sequence[float]) -> dict[str, Any]:
    """
    Return a linkage factor over the stroke, the same for both directions.

    Smooth (a random cosine and a slope over five knots), the fastest part of the
    stroke x1.4-2 the slowest, with cushions over 5 % of the stroke at each end.
    """
    low, high = limits
    share = np.linspace(0.0, 1.0, 5)
    shape = np.cos(np.pi * share + float(rng.uniform(0.0, np.pi))) + \
        float(rng.uniform(-1.0, 1.0)) * share
    shape = (shape - shape.min()) / np.ptp(shape)
    factors = np.exp(np.log(float(rng.uniform(1.4, 2.0))) * (shape - 0.5))
    return {'knots': (low + (high - low) * share).tolist(), 'factors': factors.tolist(),
            'cushion': 0.05 * (high - low), 'cushion_factor': float(rng.uniform(0.3, 0.6))}


def _load_factor(supply: float, reference: float) -> Any:
    """
    Return the speed factor of a valve without compensation fed at a fixed ``supply`` pressure.

    Lifting (positive), the load pressure resists: the flow is ``sqrt(supply - L)`` over
    its value at the ``reference`` load; lowering, it helps: ``sqrt(supply + L)``.
    """
    def factor(load: float, direction: float) -> float:
        if direction > 0.0:
            return math.sqrt(max(supply - load, 0.0025 * supply) / (supply - reference))
        return math.sqrt((supply + load) / (supply + reference))
    return factor


def hide(word: str, rng: np.random.Generator, units: str) -> tuple[Truth, dict[str, Any]]:
    """
    Return a true joint and the model file of a nominal model that misses ``word``.

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
    tuple
        ``(truth, nominal model file)``.

    """
    base = _base(rng, units)
    rest = UNITS[units][1]
    nominal = dict(base)
    joint = {'speed_map': _speed_map(base), 'delay': base['delay'],
             'stops': tuple(base['angle_limits'])}
    effects: dict[str, Any] = {}
    other = None
    if word == 'dead_zone':
        # A linear nominal model (or one with no width about the rest) of a dead-zone joint
        # whose sides have one slope (a linear model cannot tell the sides apart either).
        base = _chords(base, equal=True)
        joint['speed_map'] = _speed_map(base)
        nominal = {k: v for k, v in base.items() if k not in ('dead_zone', 'slope')}
        slope = base['slope'][1]
        nominal.update({'kind': 'linear', 'gain': slope} if rest == 0.0 else
                       {'dead_zone': [rest, rest], 'slope': [slope, slope]})
    elif word == 'velocity_saturation':
        nominal = _chords(base, equal=False)
    elif word == 'asymmetry':
        nominal = _symmetric(base, rest)
    elif word == 'time_delay':
        shift = max(0.03, 0.5 * base['delay']) * float(rng.choice([-1.0, 1.0]))
        wrong = base['delay'] + shift if base['delay'] + shift >= 0.01 else \
            base['delay'] + abs(shift)
        nominal = {**base, 'delay': round(wrong, 2)}
    elif word == 'direction_dependent_delay':
        later = base['delay'] + max(0.05, float(rng.uniform(0.4, 0.8)) * base['delay'])
        slower = round(min(later, 0.45), 2)
        split = (base['delay'], slower) if rng.random() < 0.5 else (slower, base['delay'])
        joint.update(delay=split[0], delay_negative=split[1])
        effects['direction_dependent_delay'] = {'positive': split[0], 'negative': split[1]}
    elif word == 'angle_limits':
        nominal = {**base, 'angle_limits': None}
    elif word == 'valve_lag':
        joint['lag'] = float(rng.uniform(0.05, 0.3))
        effects['valve_lag'] = {'time_constant': joint['lag']}
    elif word == 'backlash':
        joint['play'] = float(rng.uniform(1.0, 3.0))
        effects['backlash'] = {'play': joint['play']}
    elif word == 'angle_dependent_velocity':
        joint['gravity'] = (float(rng.uniform(0.2, 0.4)), float(rng.uniform(0.0, 360.0)))
        effects['angle_dependent_velocity'] = dict(zip(('amplitude', 'phase'),
                                                       joint['gravity']))
    elif word == 'stroke_geometry':
        stroke = _stroke(rng, base['angle_limits'])
        joint['stroke'] = Stroke(tuple(stroke['knots']), tuple(stroke['factors']),
                                 stroke['cushion'], stroke['cushion_factor'])
        effects['stroke_geometry'] = stroke
    elif word == 'flow_sharing':
        # The pump gives 1.05-1.3 full demands of this joint (alone it never runs short);
        # the other joint's 25-45 deg/s count as one: both at full speed ask for twice it.
        # A full demand of this joint is its top speed in that direction (as the model
        # file has it).
        low, high = base['saturation_velocity']
        other_speed = float(rng.uniform(20.0, 40.0))
        full = float(rng.uniform(0.6, 1.2))
        joint['sharing'] = (float(rng.uniform(1.05, 1.3)), high, -low, other_speed / full,
                            other_speed / full)
        other = Joint(SpeedMap('exp', (-1.0, 1.0), (other_speed, other_speed), (0.8, 0.8)),
                      delay=0.1, stops=(-40.0, 40.0))
    elif word == 'oscillation':
        # The link rings on the oil column: 1.5-4 Hz, lightly damped.
        joint['mode'] = (float(rng.uniform(1.5, 4.0)), float(rng.uniform(0.05, 0.2)))
        effects['oscillation'] = dict(zip(('frequency', 'damping'), joint['mode']))
    elif word == 'load_dependence':
        reference = float(rng.uniform(20.0, 60.0))
        joint['load_factor'] = _load_factor(float(rng.uniform(2.0, 3.0)) * 150.0, reference)
    truth_file = {**base, 'effects': effects}
    if word == 'none':
        nominal = truth_file
    nominal = {**nominal, 'effects': {k: v for k, v in effects.items()
                                      if k != word or word == 'none'}}
    return Truth(truth_file, Joint(**joint), other), nominal


def make_case(word: str, kind: str, units: str, seed: int, *, seconds: float = 60.0,
              dt: float = 0.01, noise: float = 0.02, records: int = 3) -> GridCase:
    """
    Return one case: joint, nominal model, estimation records and one validation record.

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
    records : int
        Records made: all but the last for estimation, the last for validation.

    Returns
    -------
    GridCase
        The case.

    """
    rng = np.random.default_rng([seed, WORDS.index(word), PROGRAMS.index(kind),
                                 list(UNITS).index(units)])
    truth, nominal = hide(word, rng, units)
    truth = replace(truth, joint=replace(truth.joint, noise=noise))
    made = records_of(truth, kind, rng, seconds=seconds, dt=dt, count=records,
                      loaded=word == 'load_dependence', name=f'{word} {kind} {units} {seed}')
    return GridCase(word, kind, units, truth, JointModel.from_mapping(nominal),
                    tuple(made[:-1]), (made[-1],))


def records_of(truth: Truth, kind: str, rng: np.random.Generator, *, seconds: float = 60.0,
               dt: float = 0.01, count: int = 3, loaded: bool = False,
               name: str = 'generated') -> list[Record]:
    """
    Return records of a true joint driven by one of the grid's programs.

    Parameters
    ----------
    truth : Truth
        The true joint (with the other joint on its pump, if any).
    kind : str
        One of :data:`PROGRAMS`.
    rng : numpy.random.Generator
        Random draws.
    seconds : float
        Length of each record, s.
    dt : float
        Sample period, s.
    count : int
        Records made.
    loaded : bool
        Whether each record carries a measured load (its own payload).
    name : str
        Start of each record's source.

    Returns
    -------
    list[Record]
        The records.

    """
    planner = truth.model
    machine = replace(truth.machine, dt=dt)
    made = []
    # Each record its own payload, spread over the range; the last (the validation
    # record's) in the middle of those before it, not beyond what they saw.
    spread = np.linspace(10.0, 120.0, count)
    middle = count // 2
    payloads = np.r_[rng.permutation(np.delete(spread, middle)), spread[middle]]
    for index in range(count):
        v, y0 = program(planner, kind, rng, seconds, dt)
        commands = v[:, None] if truth.other is None else np.column_stack(
            [v, other_levels(rng, v.size, dt)])
        load = load_signal(rng, v.size, dt, float(payloads[index])) if loaded else None
        made.append(record(machine, commands, angles0=[y0, 0.0][:commands.shape[1]],
                           load=load, seed=int(rng.integers(1 << 30)),
                           source=f'{name} #{index}'))
    return made


def run_case(case: GridCase, **options: Any) -> GridResult:
    """Diagnose one case and return what was named."""
    result = diagnose(case.estimation, case.model, validation=case.validation, **options)
    return GridResult(case.word, case.program, case.units, result.effect, result.mae_before,
                      result.mae_after)

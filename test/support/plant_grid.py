"""
The diagnosis grid on the physics plant, where its physics allow (docs/methods.md 8.7).

Each case is records of the physics plant (:mod:`hydro_sdp.core.synthetic.physics`: spool
valve, pump, cylinder, linkage, end stops; :mod:`support.plant_programs`) with an effect
present, and a model that lacks exactly one word. The plant is not an SDP model, so no
"true" model file exists: every model is identified from plant runs by
:func:`hydro_sdp.core.identification.identify.identify` (told the valve's neutral and
command range, as ``hydro-sdp identify --rest`` is), on runs of the same program as the
diagnosis data at other seeds and duties, and then:

* removed from the model identified on the full behaviour (the effect is there in the
  identification runs, and identify found it), a ``power_sat`` model (the family
  identify's auto choice gives the plant's full strokes, ``config/physics_arm_model.yaml``;
  named to skip the choice): ``dead_zone`` (the map's edges closed onto the neutral: the
  valve's spool overlap), ``velocity_saturation`` (the map replaced by its chords to two
  thirds of its speed at the full command: the pump's flow limit and the notches levelling
  off), ``asymmetry`` (both sides replaced by one power_sat side fitted to their average:
  piston against annulus area, the retracting notches), ``time_delay`` (the delay moved
  by 0.1 s or 40 %: the valve's dead time), ``angle_limits`` (the stroke ends, full
  strokes only: levels turned back before the stops never show them), ``valve_lag`` (the
  spool's lag) and ``stroke_geometry`` (the linkage, when identify kept a factor: it does
  so only when held-out runs need it). The map words were once taken from an ``sdp``
  model; that was unfair on the plant: eq. (5) cannot follow the valve's convex opening,
  and on the arm's strokes the ``sdp`` model *with* saturation predicted worse (validation
  MAE 2.47 deg) than its own chords without it (1.41 deg), so the "missing" word was
  missing from nothing;
* absent or not excited in the identification runs: ``flow_sharing`` (identified with
  the other joint still; the diagnosis runs have the other joint of the excavator on
  the same pump moving at random levels and resting at its neutral between them) and
  ``load_dependence`` (the boom of ``config/physics_boom_power.yaml``: its valve without
  pressure compensation, on a pump whose power binds; identified lifting nothing;
  diagnosed on runs lifting nothing and 600 kg with the piston-side pressure logged as
  the load);
* ``oscillation`` (the boom of ``config/physics_boom_compressible.yaml``: its link rings
  on a soft oil column at about 2 Hz): identified on the same plant with its pressures
  settled at every sample (no compressibility section), diagnosed on runs of the
  ringing one; the floor is that model's error on the settled plant's validation runs;
* ``none``: the ``power_sat`` model itself, on the same kind of runs.

The gap a removed word leaves is the validation MAE above that of the model it was
removed from (its *floor*, :attr:`PlantCase.floor`), and that is what the named word must
halve. The family does not follow the plant exactly, and on full strokes the slow 60 %
validation strokes integrate what it misses: on seed 0 the arm's model identified with
everything errs 1.07 deg (signed percent) and 1.09 deg (0..100 %), 2.8 deg on its +60 %
stroke alone, and the boom's 0.54 and 0.55 deg. Measured against zero, a word whose
restoring the identified model itself could not halve the error was a case no answer
passes: without its sides the arm errs 1.51 deg (half: 0.76, below that floor), without
its spool lag 1.49 and 1.40 deg (the lag, named, refitted to 1.06 and 1.08 deg: the floor),
without its linkage factor 1.30 and 1.35 deg. A word whose removal does not raise the
validation MAE at all (the random levels' sides: the model with them drifts further, 8.06
against 5.84 deg on the arm) hides nothing the runs can show: no case is made of it.
``flow_sharing``'s floor is the model's own error on the program's validation runs with
the other joint still: measured against zero, the model's error where the partner does
nothing counted as a gap no pump word can close (the arm's strokes: 1.06 deg of the
1.80). A partner that costs the model nothing on the validation runs makes no case.

The diagnosis strokes run at five duties each way, from 40 % (:data:`DUTIES`), as many as
the model was identified from and more: a ``power_sat`` side has four parameters (its
edge, its speed, its curvature, its exponent), and three duties from 50 % (the grid had
them) leave the convex opening between the edge and 75 % free. Every refit of the sides
then matched those three speeds and missed the 60 % validation strokes, and the sides
were never named (docs/methods.md 8.7).

Left out, with the reason from the plant's physics (:data:`LEFT_OUT`):
``direction_dependent_delay`` and ``backlash``. ``angle_dependent_velocity`` (a
factor of the angle opposite for the two directions: gravity through a valve without
compensation) is what identify's ``stroke_geometry`` fits as its per-direction part,
so the plant cannot give a model that lacks it and nothing else.

Varied: the joints (arm, boom), units (signed percent, a 0..100 % duty resting at 50,
volts), programs (random levels with rests, full strokes stop to stop), seeds; each
seed draws the valve's dead time (0.12-0.3 s) and spool lag (0.12-0.35 s).

"""

from __future__ import annotations

from dataclasses import dataclass, replace
from functools import cached_property, lru_cache
from typing import Any, Sequence

from hydro_sdp.core.diagnosis.residuals import mae, runs_of
from hydro_sdp.core.diagnosis.search import diagnose
from hydro_sdp.core.identification.identify import identify
from hydro_sdp.core.model.joint_model import JointModel
from hydro_sdp.core.model.records import Record
from hydro_sdp.core.model.static_maps import PowerSatMap, SdpDzMap, StaticMap
from hydro_sdp.core.synthetic.physics.plant import Machine, with_payload
import numpy as np
from scipy.optimize import least_squares
from support.grid_results import GridResult
from support.plant_programs import levels, strokes, variant, VARIANTS

#: The words hidden in turn, and ``none``.
WORDS: tuple[str, ...] = (
    'dead_zone', 'velocity_saturation', 'asymmetry', 'time_delay', 'angle_limits',
    'valve_lag', 'stroke_geometry', 'none', 'flow_sharing', 'load_dependence', 'oscillation')

#: Words the plant cannot produce, and why (its physics).
LEFT_OUT: dict[str, str] = {
    'direction_dependent_delay': 'one spool, one dead time and one lag for both directions '
                                 '(Valve.dead_time, Valve.time_constant)',
    'backlash': 'the linkage is a rigid triangle on its pins and the link rides on a linear '
                'second-order compliance: nothing is lost at a reversal',
    'angle_dependent_velocity': "identify fits the plant's opposite factor of the angle as "
                                "stroke_geometry's per-direction part: no model lacks it alone",
}

#: The two programs.
PROGRAMS: tuple[str, ...] = ('random', 'stroke')

#: Share of the gap the named word must remove: half, and 30 % for load_dependence
#: (the load acts through the pressure the pump's power leaves, not through a factor
#: the model holds: the word fits it to the logged pressure).
SHRINK = {'load_dependence': 0.7}

#: Payloads of the load_dependence runs, kg (identified at the first).
PAYLOADS = (0.0, 600.0)

#: Largest delay the diagnosis considers, s (``diagnose``'s default, passed to it by
#: :func:`run_case`): the floor's MAE is taken on the validation runs as it takes its own.
MAX_DELAY = 0.5


@dataclass(frozen=True, eq=False)
class PlantCase:
    """
    One case of the plant grid.

    Parameters
    ----------
    word : str
        The word the model lacks (``none``: nothing).
    program : str
        ``random`` or ``stroke``.
    joint, units : str
        A key of :data:`support.plant_programs.VARIANTS`.
    model : JointModel
        The model under test.
    estimation, validation : tuple of Record
        Plant records.
    floor : float
        Validation MAE of the model the word was removed from, degrees; for
        ``flow_sharing`` the model's on the same program with the other joint still; for
        ``oscillation`` the settled plant's model on its own validation runs; 0 for
        ``load_dependence`` and ``none``.

    """

    word: str
    program: str
    joint: str
    units: str
    model: JointModel
    estimation: tuple[Record, ...]
    validation: tuple[Record, ...]
    floor: float = 0.0


#: Duties of the full strokes, percent: identification, estimation (the low duties pin a
#: side's convex opening), validation.
DUTIES = {'identify': (45.0, 65.0, 85.0, 100.0), 'estimate': (40.0, 55.0, 70.0, 85.0, 100.0),
          'validate': (60.0, 90.0)}
#: Fewer and faster strokes, for a quick look (the tests).
QUICK_DUTIES = {'identify': (50.0, 75.0, 100.0), 'estimate': (55.0, 100.0),
                'validate': (70.0,)}


#: The parts of a case's runs, each drawn apart.
PARTS = ('identify', 'estimate', 'validate')


def _runs(machine: Machine, program: str, seed: int, part: str, *, seconds: float,
          pressure: bool = False) -> list[Record]:
    """
    Identification, estimation or validation runs of one program.

    Random levels last ``seconds`` s; below 40 s the strokes are the quick ones.
    """
    if program == 'stroke':
        duties = (DUTIES if seconds >= 40.0 else QUICK_DUTIES)[part]
        return strokes(machine, duties, 1000 * seed + 100 * PARTS.index(part),
                       pressure=pressure)
    count = {'identify': 3, 'estimate': 2, 'validate': 1}[part]
    return [levels(machine, seconds, 1000 * seed + 100 * PARTS.index(part) + k,
                   pressure=pressure) for k in range(count)]


def _identify(machine: Machine, records: Sequence[Record], kind: str) -> JointModel:
    """Identify the first joint, told its valve's neutral and command range."""
    valve = machine.joints[0].valve
    bare = [Record(r.t, r.v, r.y, r.joint, r.source) for r in records]
    return identify(bare, kind=kind, rest=valve.neutral, input_limits=valve.limits).model


class Identified:
    """
    A plant of one case's draws, its identification runs, its models and diagnosis runs.

    The runs are made and the models identified when first asked for.

    Parameters
    ----------
    joint, units, program : str
        The case.
    seed : int
        Seed of the draws and the runs.
    seconds : float
        Length of each random-level run, s.

    """

    def __init__(self, joint: str, units: str, program: str, seed: int,
                 seconds: float) -> None:
        self.machine = variant(joint, units, _rng(joint, units, program, seed, 0))
        self.program, self.seed, self.seconds = program, seed, seconds

    def runs(self, part: str) -> list[Record]:
        """Return the ``identify``, ``estimate`` or ``validate`` runs."""
        return _runs(self.machine, self.program, self.seed, part, seconds=self.seconds)

    @cached_property
    def identification(self) -> list[Record]:
        """Return the runs the models are identified on."""
        return self.runs('identify')

    @cached_property
    def power_sat(self) -> JointModel:
        """Return the ``power_sat`` model (the family the auto choice gives full strokes)."""
        return _identify(self.machine, self.identification, 'power_sat')

    @cached_property
    def sdp(self) -> JointModel:
        """Return the ``sdp`` model (eq. (5): the family whose features the map words are)."""
        return _identify(self.machine, self.identification, 'sdp')

    @cached_property
    def estimation(self) -> tuple[Record, ...]:
        """Return the runs the diagnosis fits on."""
        return tuple(self.runs('estimate'))

    @cached_property
    def validation(self) -> tuple[Record, ...]:
        """Return the runs the diagnosis is judged on."""
        return tuple(self.runs('validate'))


def _rng(joint: str, units: str, program: str, seed: int, tag: int) -> np.random.Generator:
    return np.random.default_rng([seed, list(VARIANTS).index((joint, units)),
                                  PROGRAMS.index(program), tag])


@lru_cache(maxsize=2)
def identified(joint: str, units: str, program: str, seed: int,
               seconds: float = 40.0) -> Identified:
    """Return the :class:`Identified` of one case's draws (the last two kept)."""
    return Identified(joint, units, program, seed, seconds)


def _top_commands(static_map: StaticMap, edges: tuple[float, float],
                  limits: tuple[float, float]) -> tuple[float, float]:
    """Commands where the map reaches two thirds of its speed at the full command, each side."""
    ends = []
    for edge, limit in zip(edges, limits):
        v = np.linspace(edge, limit, 2001)[1:]
        speeds = np.abs(static_map.rate(v))
        ends.append(float(v[np.argmax(speeds >= 2.0 / 3.0 * speeds[-1])]))
    return ends[0], ends[1]


def _chords(static_map: PowerSatMap, limits: tuple[float, float]) -> SdpDzMap:
    """Return the map's chords from its edges to two thirds of its full-command speed."""
    edges = static_map.dead_zone
    ends = _top_commands(static_map, edges, limits)
    rates = static_map.rate(np.array(ends))
    return SdpDzMap(dead_zone=edges, slope=(float(rates[0] / (ends[0] - edges[0])),
                                            float(rates[1] / (ends[1] - edges[1]))))


def _symmetric(static_map: PowerSatMap, rest: float, limits: tuple[float, float]
               ) -> PowerSatMap:
    """One power_sat side fitted to the mean of the two sides' speeds, mirrored about ``rest``."""
    half = min(rest - limits[0], limits[1] - rest)
    u = np.linspace(0.0, half, 201)
    target = 0.5 * (static_map.rate(rest + u) - static_map.rate(rest - u))
    width = 0.5 * (static_map.dead_zone[1] - static_map.dead_zone[0])

    def build(p: np.ndarray) -> PowerSatMap:
        speed, curvature, exponent, edge = np.exp(p)
        return PowerSatMap((rest - edge, rest + edge), (-speed, speed),
                           (curvature, curvature), (exponent, exponent))
    top = float(np.max(target))
    start = [1.2 * top, 1.0 / half, float(np.mean(static_map.exponent)),
             max(width, 1e-3 * half)]
    fit = least_squares(lambda p: build(p).rate(rest + u) - target, np.log(start))
    return build(fit.x)


def _without(word: str, found: Identified, rng: np.random.Generator) -> JointModel | None:
    """Return the identified model without ``word`` (None: identify did not find it)."""
    full = found.power_sat
    valve = found.machine.joints[0].valve
    static_map = full.static_map
    assert isinstance(static_map, PowerSatMap)
    if word == 'dead_zone':
        closed = (valve.neutral, valve.neutral)
        return replace(full, static_map=replace(static_map, dead_zone=closed))
    if word == 'velocity_saturation':
        return replace(full, static_map=_chords(static_map, valve.limits))
    if word == 'asymmetry':
        return replace(full, static_map=_symmetric(static_map, valve.neutral, valve.limits))
    if word == 'time_delay':
        shift = max(0.1, 0.4 * full.delay) * float(rng.choice([-1.0, 1.0]))
        wrong = full.delay + shift if full.delay + shift >= 0.01 else full.delay + abs(shift)
        return replace(full, delay=round(wrong, 2))
    if word == 'angle_limits':
        return replace(full, angle_limits=None) if full.angle_limits else None
    if word in ('valve_lag', 'stroke_geometry'):
        return full.without_effect(word) if full.effect(word) is not None else None
    return full


def _exogenous(word: str, joint: str, units: str, program: str, seed: int, seconds: float
               ) -> tuple[JointModel, list[Record], list[Record], float] | None:
    """Return the model, the runs and the floor of ``flow_sharing`` and ``load_dependence``."""
    if word == 'flow_sharing':
        # The same draws: the joint of identified(), with the other on its pump.
        found = identified(joint, units, program, seed, seconds)
        shared = variant(joint, units, _rng(joint, units, program, seed, 0), partner=True)
        # The floor: the model's own error on the program's validation runs with the
        # other joint still, what no word of the pump's share can remove.
        alone = _runs(found.machine, program, seed + 500, 'validate', seconds=seconds)
        validation = _runs(shared, program, seed + 500, 'validate', seconds=seconds)
        floor = mae(found.power_sat, runs_of(alone, MAX_DELAY, settle=0.0))
        if floor >= mae(found.power_sat, runs_of(validation, MAX_DELAY, settle=0.0)):
            return None  # The other joint costs the model nothing the runs show.
        return (found.power_sat,
                _runs(shared, program, seed + 500, 'estimate', seconds=seconds),
                validation, floor)
    if joint != 'boom':
        return None  # The arm's compensated valve holds its speed under any payload.
    machine = variant(joint, units, _rng(joint, units, program, seed, 1), power=True)
    light = with_payload(machine, PAYLOADS[0])
    model = _identify(light, _runs(light, program, seed, 'identify', seconds=seconds),
                      'power_sat')
    estimation: list[Record] = []
    validation: list[Record] = []
    for payload in PAYLOADS:
        loaded = with_payload(machine, payload)
        for part, out in (('estimate', estimation), ('validate', validation)):
            out += [replace(r, source=f'{payload:g} kg {r.source}') for r in _runs(
                loaded, program, seed + int(payload), part, seconds=seconds, pressure=True)]
    return model, estimation, validation, 0.0


def _ringing(joint: str, units: str, program: str, seed: int, seconds: float
             ) -> tuple[JointModel, list[Record], list[Record], float] | None:
    """Return the model, the runs and the floor of ``oscillation`` (the boom only)."""
    if joint != 'boom':
        return None  # Only the boom's preset rings on its oil column.
    machine = variant(joint, units, _rng(joint, units, program, seed, 3), ringing=True)
    settled = replace(machine, joints=(replace(machine.joints[0], compressibility=None),))
    model = _identify(settled, _runs(settled, program, seed, 'identify', seconds=seconds),
                      'power_sat')
    floor = mae(model, runs_of(_runs(settled, program, seed, 'validate', seconds=seconds),
                               MAX_DELAY, settle=0.0))
    return (model, _runs(machine, program, seed, 'estimate', seconds=seconds),
            _runs(machine, program, seed, 'validate', seconds=seconds), floor)


def make_case(word: str, program: str, joint: str, units: str, seed: int, *,
              seconds: float = 40.0) -> PlantCase | None:
    """
    Return one case of the plant grid, or None where identify found nothing to remove.

    Parameters
    ----------
    word : str
        One of :data:`WORDS`.
    program : str
        One of :data:`PROGRAMS`.
    joint, units : str
        A key of :data:`support.plant_programs.VARIANTS`.
    seed : int
        Seed of the draws and the runs.
    seconds : float
        Length of each random-level run, s; below 40 s, fewer and faster strokes
        (:data:`QUICK_DUTIES`).

    Returns
    -------
    PlantCase or None
        The case (None too where the model the word was removed from predicts the
        validation runs no better than the case's model: the runs do not show the word).

    """
    if word in ('flow_sharing', 'load_dependence', 'oscillation'):
        made = _ringing(joint, units, program, seed, seconds) if word == 'oscillation' else \
            _exogenous(word, joint, units, program, seed, seconds)
        if made is None:
            return None
        model, estimation, validation, floor = made
        return PlantCase(word, program, joint, units, model, tuple(estimation),
                         tuple(validation), floor)
    if word == 'angle_limits' and program == 'random':
        return None
    found = identified(joint, units, program, seed, seconds)
    model = _without(word, found, _rng(joint, units, program, seed, 2 + WORDS.index(word)))
    if model is None:
        return None
    if word == 'none':
        return PlantCase(word, program, joint, units, model, found.estimation, found.validation)
    checks = runs_of(found.validation, MAX_DELAY, settle=0.0)
    floor = mae(found.power_sat, checks)
    if floor >= mae(model, checks):
        return None
    return PlantCase(word, program, joint, units, model, found.estimation, found.validation,
                     floor)


def run_case(case: PlantCase, **options: Any) -> GridResult:
    """Diagnose one case (one word added at most) and return what was named."""
    result = diagnose(case.estimation, case.model, validation=case.validation,
                      **{'max_iterations': 1, 'max_delay': MAX_DELAY, **options})
    return GridResult(case.word, case.program, f'{case.joint} {case.units}', result.effect,
                      result.mae_before, result.mae_after,
                      shrink=SHRINK.get(case.word, 0.5), floor=case.floor)

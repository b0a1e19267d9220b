"""
From a machine's recordings to a checked controller (the ``calibrate`` command).

:func:`calibrate` chains what the other commands do one at a time: identify the
joint (held-out choice of the map family), evaluate the model on validation
records, diagnose what it misses and add the named effects, design the PIP-IDZ
controller from the final model, and check it in closed loop on that final
model with its effects (:mod:`.loop_check`); when the check fails the dominant
poles move toward 1 and the controller is designed again, and the result says
so. Without validation records, whole records are held out (never a piece of a
record), and the result says which.

"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
import math
from typing import Any, Callable, Sequence

from hydro_sdp.core.control.controller_spec import ControllerSpec, design_from_model, format_pole
from hydro_sdp.core.control.loop_check import check_loop, CheckSettings, LoopCheck, slower_poles
from hydro_sdp.core.diagnosis import DETECTORS, diagnose, Diagnosis
from hydro_sdp.core.errors import DataError, HydroSdpError
from hydro_sdp.core.identification.evaluation import evaluate, RecordScore
from hydro_sdp.core.identification.identify import Identification, identify
from hydro_sdp.core.model.joint_model import JointModel
from hydro_sdp.core.model.records import Record
from hydro_sdp.core.model.static_maps import CHORD_SPEED_FRACTION, LinearMap, SdpDzMap, SdpMap
import numpy as np

#: The stages, in order, as :func:`calibrate` reports them.
STAGES = ('identify', 'evaluate', 'diagnose', 'design', 'closed-loop check')
#: Most re-designs with slower poles after a failed check.
REDESIGNS = 4

#: Progress: ``on_stage(stage, done, total)``.
StageCallback = Callable[[str, float, float], None]


@dataclass(frozen=True)
class CalibrationSettings:
    """
    Choices of a calibration.

    Parameters
    ----------
    rest : float or None
        Rest command to identify with (default: what ``identify`` finds).
    input_limits : tuple[float, float] or None
        Command range of the valve, written to the model.
    angle_limits : tuple[float, float] or None
        Known end stops, degrees (default: those seen in the data).
    control_period : float
        Control period, s.
    poles : tuple[complex, ...] or None
        Closed-loop poles to start from (default: the LQ design); fewer than the
        design needs (``1 +`` the delay in control samples) are completed with
        poles at 0.
    iterations : int
        Most effects the diagnosis adds.
    check : CheckSettings or None
        The closed-loop check (default: :class:`CheckSettings` at the records'
        sample period).

    """

    rest: float | None = None
    input_limits: tuple[float, float] | None = None
    angle_limits: tuple[float, float] | None = None
    control_period: float = 0.05
    poles: tuple[complex, ...] | None = None
    iterations: int = 4
    check: CheckSettings | None = None


@dataclass(frozen=True, eq=False)
class CalibrationResult:
    """
    Everything a calibration found.

    Parameters
    ----------
    identification : Identification
        The identification and its evidence.
    validation_note : str
        Which records the MAE is measured on (given, held out, or in-sample).
    estimation, validation : tuple[Record, ...]
        The records identified from and evaluated on.
    scores_identified, scores_final : tuple[RecordScore, ...]
        Table-2 scores of the identified and the final model on the validation records.
    diagnosis : Diagnosis
        The named effects.
    spec : ControllerSpec
        The controller written (the last design tried).
    check : LoopCheck
        Its closed-loop check on the final model.
    designs : tuple[tuple[str, ...], ...]
        Poles of every design tried, first to last.
    stroke : tuple[float, float]
        Angle range the check stepped across, degrees.
    warnings : tuple[str, ...]
        What the user should know, one line each.

    """

    identification: Identification
    validation_note: str
    estimation: tuple[Record, ...]
    validation: tuple[Record, ...]
    scores_identified: tuple[RecordScore, ...]
    scores_final: tuple[RecordScore, ...]
    diagnosis: Diagnosis
    spec: ControllerSpec
    check: LoopCheck
    designs: tuple[tuple[str, ...], ...]
    stroke: tuple[float, float]
    warnings: tuple[str, ...] = field(default=())

    @property
    def model(self) -> JointModel:
        """Return the final model: identified, with the named effects."""
        return self.diagnosis.model

    @property
    def effects(self) -> tuple[str, ...]:
        """Named effects: identify's first (a valve lag...), then the diagnosis's."""
        found = tuple(effect.name for effect in self.identification.model.effects)
        return found + tuple(step.effect for step in self.diagnosis.ledger
                             if step.effect not in found)

    @property
    def effect(self) -> str:
        """Return the first named effect, or ``none``."""
        return self.effects[0] if self.effects else 'none'

    @property
    def mae_identified(self) -> float:
        """Mean per-record validation MAE of the identified model, degrees."""
        return float(np.mean([s.model for s in self.scores_identified]))

    @property
    def mae_final(self) -> float:
        """Mean per-record validation MAE of the final model, degrees."""
        return float(np.mean([s.model for s in self.scores_final]))


def split_records(records: Sequence[Record]) -> tuple[list[Record], list[Record], str]:
    """
    Hold out whole recordings for validation: every third one, at least one of two.

    Pieces of one recording (a bag cut at a hole in its stamps shares its
    ``source``) stay together, on one side: a held-out piece of a recording the
    model was fitted on would not be held out.

    Parameters
    ----------
    records : sequence of Record
        The inputs, in the order given.

    Returns
    -------
    tuple
        ``(estimation, validation, note)``; with one recording both are all of its
        records and the note says the MAE is in-sample.

    """
    # A record without a source is a recording of its own.
    keys = [record.source or f'#{index}' for index, record in enumerate(records)]
    sources = list(dict.fromkeys(keys))
    recordings = len(sources)
    if recordings < 2:
        return list(records), list(records), ('in-sample: one record given, nothing to hold '
                                              'out (give --validation for a held-out MAE)')
    held = set(range(2, recordings, 3)) or {recordings - 1}
    kept = {sources[i] for i in held}
    estimation = [r for r, key in zip(records, keys) if key not in kept]
    validation = [r for r, key in zip(records, keys) if key in kept]
    names = ', '.join(str(i + 1) for i in sorted(held))
    return estimation, validation, (f'held out: input record{"s" if len(held) > 1 else ""} '
                                    f'{names} of {recordings} (whole records)')


def _identify(records: Sequence[Record], settings: CalibrationSettings,
              progress: Callable[[str], None]) -> Identification:
    options: dict[str, Any] = {'angle_limits': settings.angle_limits,
                               'input_limits': settings.input_limits, 'progress': progress}
    return identify(records, rest=settings.rest, **options)


#: Speed, as a fraction of the speed at the end of the span, that the chord of a
#: convex map passes through on its way to the two-thirds point.
CREEP_SPEED_FRACTION = 0.02


def chord_map(model: JointModel, span: tuple[float, float]) -> SdpDzMap:
    """
    SDP-DZ chords of any monotone map, as the IDZ of an ``sdp`` map (docs/methods.md 3.3).

    On each side of rest the chord ends where the speed reaches two thirds of its
    value at the end of ``span``; its edge is the outer of where the speed first
    exceeds 0.1 % of that value and where the line through the points at 2 %
    (:data:`CREEP_SPEED_FRACTION`) and two thirds meets zero speed. For a map that
    leaves its dead-zone steeply (``sdp``, ``pwl``) that is the dead-zone edge; a
    convex map (``power_sat``) creeps for a long way past its dead-zone, and an
    IDZ edge there leaves the integral action to wind through commands that barely
    move the joint: on the physics plant's arm the edge moves from 28 % to 37 %
    duty, and the limit cycles of the held set-points go.

    Parameters
    ----------
    model : JointModel
        The joint (any map family).
    span : tuple[float, float]
        Commands the map is trusted over (the measured levels), input units.

    Returns
    -------
    SdpDzMap
        Dead-zone edges and chord slopes.

    """
    rest = model.rest_command
    edges, slopes = [], []
    for end, sign in ((span[0], -1.0), (span[1], 1.0)):
        v = np.linspace(rest, end, 2001)
        speed = sign * model.rate(v)
        top = float(speed[-1])
        if not (sign * (end - rest) > 0.0 and top > 0.0):
            raise DataError(f'the {model.kind} map does not move the joint '
                            f'{"down" if sign < 0 else "up"} within the commands measured')
        leaves = float(v[max(int(np.argmax(speed > 1e-3 * top)) - 1, 0)])
        creep = float(v[int(np.argmax(speed >= CREEP_SPEED_FRACTION * top))])
        reach = float(v[int(np.argmax(speed >= CHORD_SPEED_FRACTION * top))])
        secant = (CHORD_SPEED_FRACTION - CREEP_SPEED_FRACTION) * top / max(
            abs(reach - creep), 1e-12)
        meets = creep - sign * CREEP_SPEED_FRACTION * top / secant
        edge = leaves if sign * (leaves - meets) >= 0.0 else meets
        edges.append(edge)
        slopes.append(CHORD_SPEED_FRACTION * top / max(abs(reach - edge), 1e-12))
    return SdpDzMap(dead_zone=(edges[0], edges[1]), slope=(slopes[0], slopes[1]))


def _design_model(model: JointModel, identified: Identification,
                  warnings: list[str]) -> JointModel:
    """Return the model the IDZ is designed from: the model, or its SDP-DZ chords."""
    if isinstance(model.static_map, (SdpMap, SdpDzMap, LinearMap)):
        return model
    levels = [p.level for p in identified.points]
    span = (min(levels), max(levels))
    if model.input_limits is not None:
        span = (max(span[0], model.input_limits[0]), min(span[1], model.input_limits[1]))
    chord = chord_map(model, span)
    warnings.append(f'the IDZ inverts chords of the {model.kind} map: dead-zone '
                    f'[{chord.dead_zone[0]:.4g}, {chord.dead_zone[1]:.4g}], slopes '
                    f'{chord.slope[0]:.4g}, {chord.slope[1]:.4g} deg/s per unit')
    return replace(model, static_map=chord)


def _clean(poles: Sequence[complex]) -> list[complex]:
    """Round away the scatter of computed eigenvalues, so that pairs stay conjugate."""
    return [complex(round(p.real, 9), round(p.imag, 9)) for p in (complex(x) for x in poles)]


def _stroke(model: JointModel, records: Sequence[Record]) -> tuple[float, float]:
    if model.angle_limits is not None:
        return model.angle_limits
    low = min(float(np.min(r.y)) for r in records)
    high = max(float(np.max(r.y)) for r in records)
    if not high - low > 1.0:
        raise DataError(f'the joint moved only {high - low:.2f} deg in the records; the '
                        'closed-loop check needs the stroke (give --angle-limits)')
    return low, high


def calibrate(records: Sequence[Record], validation: Sequence[Record] | None = None,
              settings: CalibrationSettings | None = None, *,
              on_stage: StageCallback | None = None) -> CalibrationResult:
    """
    Identify, evaluate, diagnose, design and check a joint's controller.

    Parameters
    ----------
    records : sequence of Record
        Recordings of one joint (step experiments, full-stroke runs, random levels).
    validation : sequence of Record or None
        Held-out recordings; default: whole records held out of ``records``.
    settings : CalibrationSettings or None
        Choices; default :class:`CalibrationSettings`.
    on_stage : callable or None
        Progress, called as ``on_stage(stage, done, total)`` with a stage of
        :data:`STAGES`.

    Returns
    -------
    CalibrationResult
        The models, the controller, the check and the warnings.

    """
    settings = settings if settings is not None else CalibrationSettings()
    if not records:
        raise DataError('no records to calibrate from')
    report: StageCallback = on_stage if on_stage is not None else (lambda s, d, t: None)
    warnings: list[str] = []
    if validation:
        estimation, checks = list(records), list(validation)
        note = f'given: {len(checks)} validation record{"s" if len(checks) > 1 else ""}'
    else:
        estimation, checks, note = split_records(records)
        if note.startswith('in-sample'):
            warnings.append('one record: the validation MAE is in-sample')
    stages = ['segmenting', 'estimating the delay', 'fitting the static map',
              'comparing map families on held-out experiments']
    report('identify', 0, len(stages))
    identified = _identify(estimation, settings,
                           lambda name: report('identify', stages.index(name), len(stages)))
    model = identified.model
    report('evaluate', 0, 2)
    scores = tuple(evaluate(checks, model))
    report('evaluate', 1, 2)
    words = max(1, settings.iterations)
    done = [0]

    def tick(_: str) -> None:
        done[0] += 1
        report('diagnose', done[0], len(DETECTORS) * words)
    report('diagnose', 0, len(DETECTORS) * words)
    diagnosis = diagnose(estimation, model, validation=checks, max_iterations=settings.iterations,
                         progress=tick)
    final = diagnosis.model
    final_scores = tuple(evaluate(checks, final))
    report('design', 0, 1)
    design_model = _design_model(final, identified, warnings)
    spec = design_from_model(design_model, control_period=settings.control_period)
    if settings.poles is not None:
        # The number of poles depends on the delay found: the rest are deadbeat (at 0).
        poles = list(settings.poles) + [0j] * max(0, len(spec.poles) - len(settings.poles))
        spec = design_from_model(design_model, control_period=settings.control_period,
                                 poles=poles)
    stroke = _stroke(final, list(records) + list(checks))
    check_settings = settings.check if settings.check is not None else CheckSettings(
        dt=identified.sample_period)
    designs: list[tuple[str, ...]] = []
    check: LoopCheck | None = None
    for attempt in range(REDESIGNS + 1):
        designs.append(tuple(format_pole(p) for p in spec.poles))
        report('closed-loop check', attempt, REDESIGNS + 1)
        check = check_loop(final, spec, stroke, settings=check_settings)
        if check.passed or attempt == REDESIGNS:
            break
        try:
            slower = design_from_model(design_model, control_period=settings.control_period,
                                       poles=slower_poles(_clean(list(spec.poles))))
        except HydroSdpError as error:
            warnings.append(f'no slower design could be made: {error}')
            break
        listed = ', '.join(format_pole(p) for p in slower.poles)
        warnings.append(f'closed-loop check failed ({"; ".join(check.failures)}); designed '
                        f'again with slower poles {listed}')
        spec = slower
    assert check is not None  # the loop runs at least once
    if not check.passed:
        warnings.append('the controller still fails the closed-loop check: '
                        + '; '.join(check.failures))
    if not all(math.isfinite(s.model) for s in final_scores):
        warnings.append('the final model diverges on a validation record')
    return CalibrationResult(identified, note, tuple(estimation), tuple(checks), scores,
                             final_scores, diagnosis, spec, check, tuple(designs), stroke,
                             tuple(warnings))

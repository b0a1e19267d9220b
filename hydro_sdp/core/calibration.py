"""From a machine's recordings to a checked controller: the ``calibrate`` command (methods 10)."""

from __future__ import annotations

from dataclasses import dataclass, field, replace
import math
from typing import Callable, cast, Sequence

from hydro_sdp.core.control.controller_spec import ControllerSpec, design_from_model, format_pole
from hydro_sdp.core.control.design_plant import completed_poles, mode_poles
from hydro_sdp.core.control.idz_design import default_form, faded, IdzForm
from hydro_sdp.core.control.loop_check import check_loop, CheckSettings, LoopCheck, slower_poles
from hydro_sdp.core.control.loop_obstacles import Obstacle, obstacles, standing_in_the_way
from hydro_sdp.core.control.plausible_models import (
    check_over, plausible_models, PlausibleCheck)
from hydro_sdp.core.diagnosis import DETECTORS, diagnose, Diagnosis
from hydro_sdp.core.errors import DataError, HydroSdpError
from hydro_sdp.core.identification.evaluation import evaluate, RecordScore
from hydro_sdp.core.identification.family_choice import FittedKind
from hydro_sdp.core.identification.identify import Identification, identify, IdentifyStage
from hydro_sdp.core.model.joint_model import JointModel
from hydro_sdp.core.model.records import Record
from hydro_sdp.core.model.sample_period import control_period_on, ControlPeriod
from hydro_sdp.core.model.timing import SamplePeriod
import numpy as np

#: The stages, in order, as :func:`calibrate` reports them.
STAGES = ('identify', 'evaluate', 'diagnose', 'design', 'closed-loop check', 'plausible machines')
#: Most re-designs with slower poles after a failed check.
REDESIGNS = 4

#: Progress: ``on_stage(stage, done, total)``.
StageCallback = Callable[[str, float, float], None]


@dataclass(frozen=True)
class CalibrationSettings:
    """
    Choices of a calibration.

    Attributes
    ----------
    rest : float or None
        Rest command to identify with (default: what ``identify`` finds).
    input_limits : tuple[float, float] or None
        Command range of the valve, written to the model.
    angle_limits : tuple[float, float] or None
        Known end stops, degrees (default: those seen in the data).
    control_period : float
        Control period asked for, s; the controller runs at the nearest whole multiple of the
        records' sample period (:func:`.sample_period.control_period_on`).
    poles : tuple[complex, ...] or None
        Closed-loop poles to start from (default: the LQ design); fewer than the design needs
        (``1 +`` the delay in control samples) are completed with poles at 0.
    check : CheckSettings or None
        The closed-loop check (default: :class:`CheckSettings` at the records' sample period).

    """

    rest: float | None = None
    input_limits: tuple[float, float] | None = None
    angle_limits: tuple[float, float] | None = None
    control_period: SamplePeriod = SamplePeriod(0.05)
    poles: tuple[complex, ...] | None = None
    iterations: int = 4
    check: CheckSettings | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, 'control_period', SamplePeriod(self.control_period))


@dataclass(frozen=True)
class DesignFigures:
    """
    One design's closed-loop figures, for the trade of settling against chatter.

    Attributes
    ----------
    fade : float
        The IDZ's fade-in band, degrees per control sample (0: the chatter band alone).
    settling : tuple[float, float]
        Shortest and longest settling time of the steps, s.
    overshoot : float
        Largest overshoot, percent.
    pulse_rate : float
        Valve pulses across the dead-zone per second of hold.
    travel_rate : float
        Valve travel per second of hold, input units.
    travel_share : float or None
        The same as a share of the valve range.

    """

    fade: float
    passed: bool
    settling: tuple[float, float]
    overshoot: float
    pulse_rate: float
    travel_rate: float
    travel_share: float | None

    @classmethod
    def of(cls, spec: ControllerSpec, check: LoopCheck) -> DesignFigures:
        """Return the figures of a design and its check."""
        chatter = check.chatter
        return cls(0.0 if spec.idz is None else spec.idz.fade, check.passed,
                   check.settling_range,
                   float(max((m.overshoot for m in check.steps), default=0.0)),
                   chatter.pulse_rate, chatter.travel_rate, chatter.travel_share)


@dataclass(frozen=True, eq=False)
class CalibrationResult:
    """
    Everything a calibration found.

    Attributes
    ----------
    validation_note : str
        Which records the MAE is measured on (given, held out, or in-sample).
    scores_identified, scores_final : tuple[RecordScore, ...]
        Table-2 scores of the identified and the final model on the validation records.
    stroke : tuple[float, float]
        Angle range the check stepped across, degrees.
    forms : tuple[str, ...]
        IDZ form of every design tried (``chord`` or ``table``), first to last.
    obstacles : tuple[Obstacle, ...]
        When the check failed: the check with each element idealised.
    control : ControlPeriod or None
        The control period, as whole samples of the records' period.
    trade : tuple[DesignFigures, ...]
        When the IDZ pulsed at hold: the design with the chatter band alone, then the one whose
        compensation fades in (settling against chatter); else empty.
    fades : tuple[float, ...]
        IDZ fade-in band of every design tried, first to last (0: none).
    plausible : PlausibleCheck or None
        The final controller's check on the models the data do not rule out.

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
    forms: tuple[str, ...] = field(default=())
    obstacles: tuple[Obstacle, ...] = field(default=())
    control: ControlPeriod | None = None
    trade: tuple[DesignFigures, ...] = field(default=())
    fades: tuple[float, ...] = field(default=())
    plausible: PlausibleCheck | None = None

    @property
    def in_the_way(self) -> tuple[str, ...]:
        """Elements that stand in the way of a failed check (empty when it passed)."""
        if self.check.passed:
            return ()
        return standing_in_the_way(self.obstacles, len(self.check.failures))

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

    ``records``: the inputs, in the order given.
    Returns: ``(estimation, validation, note)``; with one recording both are all of its records and
    the note says the MAE is in-sample.
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


def _families_in_band(identified: Identification, final: JointModel) -> list[JointModel]:
    """Return ``final`` with the map of each other family within the held-out tie band."""
    judged = identified.family
    if judged is None or judged.chosen < 0:
        return []
    pooled, best = judged.pooled, judged.best
    models = []
    for c, name in enumerate(judged.names):
        if c == judged.chosen or not pooled[c] - pooled[best] <= judged.bands[c]:
            continue
        try:
            other = identified.family_map(cast(FittedKind, name))
        except HydroSdpError:
            continue
        models.append(replace(final, static_map=other, undetermined=tuple(
            entry for entry in final.undetermined if entry.is_edge)))
    return models


def _plausible_warning(plausible: PlausibleCheck, model: JointModel) -> str:
    """Say on which plausible models the controller fails, and what would rule them out."""
    bounded = {entry.parameter: entry.record for entry in model.undetermined}
    names = [p.name for p, _ in plausible.failed]
    pins = sorted({record for name in names for key, record in bounded.items()
                   if name.startswith(key) and record})
    first = plausible.failed[0][1].failures[0] if plausible.failed[0][1].failures else ''
    return (f'the controller passes on the identified model but fails on {len(names)} of '
            f'{len(plausible.checks)} models the data do not rule out: {", ".join(names)} '
            f'(first: {first})' + (f'; to rule them out: {"; ".join(pins)}' if pins else
                                   '; more runs at the commands that set them narrow them'))


def _identify(records: Sequence[Record], settings: CalibrationSettings,
              progress: Callable[[IdentifyStage], None]) -> Identification:
    return identify(records, rest=settings.rest, angle_limits=settings.angle_limits,
                    input_limits=settings.input_limits, progress=progress)


class _Designer:
    """Designs the controller of the final model in one IDZ form, as calibrate asks."""

    def __init__(self, model: JointModel, settings: CalibrationSettings,
                 noise_std: float) -> None:
        self.model, self.settings, self.noise_std = model, settings, noise_std
        self.form: IdzForm = 'chord'
        #: Whether the IDZ's compensation fades in (taken once a design pulsed at hold).
        self.fade = False

    def design(self, poles: Sequence[complex] | None = None,
               model: JointModel | None = None) -> ControllerSpec:
        """Design in the current form (LQ without ``poles``), for ``model`` or the final one."""
        spec = design_from_model(model if model is not None else self.model,
                                 control_period=self.settings.control_period, poles=poles,
                                 form=self.form, noise_std=self.noise_std)
        if self.fade and spec.idz is not None:
            spec = replace(spec, idz=faded(spec.idz))
        return spec

    def first(self, form: IdzForm) -> ControllerSpec:
        """Return the first design in ``form``: LQ, or the poles asked for, completed."""
        self.form = form
        spec = self.design()
        if self.settings.poles is not None:
            # The number of poles depends on the delay found: the valve lag keeps its own,
            # the rest are deadbeat (at 0).
            spec = self.design(completed_poles(spec.plant, self.settings.poles))
        return spec


def _slower(spec: ControllerSpec) -> list[complex]:
    """Return the spec's poles with the dominant ones slower, a link's mode left as it is."""
    poles = _clean(list(spec.poles))
    if spec.oscillation is None:
        return slower_poles(poles)
    pair = _clean(mode_poles(spec.oscillation, spec.control_period))
    for target in pair:
        nearest = min(range(len(poles)), key=lambda i: abs(poles[i] - target))
        if abs(poles[nearest] - target) < 0.05:
            poles[nearest] = target
    return slower_poles(poles, keep=pair)


def _clean(poles: Sequence[complex]) -> list[complex]:
    """Round away the scatter of computed eigenvalues, so that pairs stay conjugate."""
    return [complex(round(p.real, 9), round(p.imag, 9)) for p in (complex(x) for x in poles)]


def _stroke(model: JointModel, records: Sequence[Record]) -> tuple[float, float]:
    # A side without a stop: the farthest the records went.
    stops = model.angle_limits or (-math.inf, math.inf)
    low = stops[0] if math.isfinite(stops[0]) else min(float(np.min(r.y)) for r in records)
    high = stops[1] if math.isfinite(stops[1]) else max(float(np.max(r.y)) for r in records)
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

    See Also
    --------
    identify, diagnose, design_from_model : the stages one by one.

    Examples
    --------
    >>> from hydro_sdp import calibrate, save_controller
    >>> result = calibrate(records)  # doctest: +SKIP
    >>> save_controller(result.spec, 'j2_controller.yaml')  # doctest: +SKIP

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
    report('identify', 0, len(IdentifyStage))
    identified = _identify(estimation, settings,
                           lambda stage: report('identify', stage, len(IdentifyStage)))
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
    stroke = _stroke(final, list(records) + list(checks))
    noise = identified.segmentation.noise_std
    noise = noise if math.isfinite(noise) and noise > 0.0 else 0.0
    check_settings = settings.check if settings.check is not None else CheckSettings(
        dt=identified.sample_period, noise_std=noise)
    # Whole samples of the records' period: a clock a fraction of a percent off a round
    # period changes neither the samples per step nor the gains.
    control = control_period_on(settings.control_period, identified.sample_period)
    designer = _Designer(final, replace(settings, control_period=control.seconds), noise)
    spec = designer.first(default_form(final))
    designs: list[tuple[str, ...]] = []
    forms: list[str] = []
    fades: list[float] = []
    trade: list[DesignFigures] = []
    check: LoopCheck | None = None
    total = REDESIGNS + 2           # the chord, the table, then slower poles (and a fade)
    attempt = 0
    while True:
        designs.append(tuple(format_pole(p) for p in spec.poles))
        forms.append(designer.form)
        fades.append(0.0 if spec.idz is None else spec.idz.fade)
        report('closed-loop check', attempt, total)
        check = check_loop(final, spec, stroke, settings=check_settings)
        if designer.fade and len(trade) == 1:
            trade.append(DesignFigures.of(spec, check))
        attempt += 1
        if check.passed or attempt == total:
            break
        if (check.failures == check.chatter.failures and not designer.fade
                and spec.idz is not None and spec.idz.beta > 0.0):
            # The valve pulses at hold and nothing else fails: the same design with its
            # compensation fading in (one more attempt, the trade shown).
            designer.fade = True
            total += 1
            trade.append(DesignFigures.of(spec, check))
            warnings.append(f'the IDZ pulses at hold ({"; ".join(check.chatter.failures)}); '
                            'its compensation fades in beyond the chatter band instead')
            spec = replace(spec, idz=faded(spec.idz))
            continue
        if designer.form == 'chord':
            try:
                table = designer.first('table')
            except HydroSdpError as error:
                warnings.append(f'no IDZ table could be made: {error}')
            else:
                warnings.append(f'the chord IDZ fails the closed-loop check '
                                f'({"; ".join(check.failures)}); the IDZ inverts the '
                                f'{final.kind} map itself (a table) instead')
                spec = table
                continue
        try:
            slower = designer.design(_slower(spec))
        except HydroSdpError as error:
            warnings.append(f'no slower design could be made: {error}')
            break
        listed = ', '.join(format_pole(p) for p in slower.poles)
        warnings.append(f'closed-loop check failed ({"; ".join(check.failures)}); designed '
                        f'again with slower poles {listed}')
        spec = slower
    assert check is not None  # the loop runs at least once
    report('plausible machines', 0, 1)
    plausible = check_over(plausible_models(
        final, standard_errors=identified.fit.standard_errors,
        dt=identified.sample_period,
        families=_families_in_band(identified, final)),
        spec, stroke, check_settings)
    spec = replace(spec, design={**spec.design, 'checked_over': plausible.to_mapping()})
    if check.passed and plausible.failed:
        warnings.append(_plausible_warning(plausible, final))
    found: tuple[Obstacle, ...] = ()
    if not check.passed:
        warnings.append('the controller still fails the closed-loop check: '
                        + '; '.join(check.failures))
        report('closed-loop check', total, total + 1)
        found = obstacles(final, spec, stroke, check_settings,
                          lambda ideal, poles: designer.design(poles, ideal))
        named = standing_in_the_way(found, len(check.failures))
        tried = ', '.join(f'{o.element} ({"passes" if o.passed else f"{o.failures} failures"})'
                          for o in found)
        warnings.append(f'in the way: {" and ".join(named) if named else "no element alone"} '
                        f'(the check with each idealised: {tried})')
    if not all(math.isfinite(s.model) for s in final_scores):
        warnings.append('the final model diverges on a validation record')
    warnings += list(spec.notes)
    return CalibrationResult(identified, note, tuple(estimation), tuple(checks), scores,
                             final_scores, diagnosis, spec, check, tuple(designs), stroke,
                             tuple(warnings), tuple(forms), found, control, tuple(trade),
                             tuple(fades), plausible)

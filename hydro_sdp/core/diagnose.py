"""
The discrepancy workflow (docs/interfaces.md section 5).

Find where a model and measured data disagree, name the missing effect, add it,
and show the gap shrink.

The measured commands are replayed through the model; the velocity residual
``eps_k = dy_k - dy^_k`` (measured against simulated increments, docs/methods.md section 8.1)
localises a discrepancy in time without the drift of the simulation error.
For every word of the vocabulary a candidate model is built that adds that
effect and only it (a dead-zone, saturation, asymmetry, a new delay, separate
delays per direction, end stops, a valve lag, backlash, angle-dependent speed),
with its parameters fitted to the data. A candidate is *significant* when its
residuals are smaller than the model's block by block (a paired t-test over
one-second blocks, robust to the residuals' autocorrelation) and by a useful
margin; the largest significant improvement names the effect. It is kept only
if the simulation error on the validation records shrinks, and the search
repeats on the augmented model until nothing significant is left: ``none``.

"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
import math
from typing import Callable, Sequence

from hydro_sdp.core.arrays import FloatArray
from hydro_sdp.core.delay import estimate_delay, level_speeds
from hydro_sdp.core.effects import (
    AngleDependentVelocity, Backlash, DirectionDependentDelay, ValveLag)
from hydro_sdp.core.errors import DataError, HydroSdpError
from hydro_sdp.core.experiments import check_record, segment_records, split_long, thin
from hydro_sdp.core.map_fit import fit_sdp, FitData
from hydro_sdp.core.model import JointModel
from hydro_sdp.core.programs import rest_command
from hydro_sdp.core.records import Record
from hydro_sdp.core.simulation import one_step_increments, simulate, speed_profile
from hydro_sdp.core.static_maps import LinearMap, SdpDzMap, SdpMap
import numpy as np
from scipy.optimize import least_squares, minimize_scalar

VOCABULARY = ('dead_zone', 'velocity_saturation', 'asymmetry', 'time_delay',
              'direction_dependent_delay', 'angle_limits', 'valve_lag', 'backlash',
              'angle_dependent_velocity')
#: A candidate is significant when its block-paired t statistic exceeds this...
T_LIMIT = 3.0
#: ...and it removes at least this share of the squared velocity residual.
MIN_GAIN = 0.02
BLOCK_SECONDS = 1.0


@dataclass(frozen=True)
class Candidate:
    """
    One effect tried on the data.

    Parameters
    ----------
    effect : str
        Vocabulary word.
    applicable : bool
        Whether the effect can be added to this model at all.
    gain : float
        Share of the squared velocity residual the effect removes (estimation data).
    t : float
        Block-paired t statistic of that reduction.
    significant : bool
        Whether ``t`` and ``gain`` pass the thresholds.
    parameters : dict
        Fitted parameters of the effect.
    evidence : str
        What in the data shows it.

    """

    effect: str
    applicable: bool
    gain: float = 0.0
    t: float = 0.0
    significant: bool = False
    parameters: dict = field(default_factory=dict)
    evidence: str = ''


@dataclass(frozen=True)
class LedgerStep:
    """
    One iteration of the workflow.

    Parameters
    ----------
    effect : str
        The effect added.
    parameters : dict
        Its fitted parameters.
    mae_before : float
        Validation simulation MAE before adding it, degrees.
    mae_after : float
        The same after.

    """

    effect: str
    parameters: dict
    mae_before: float
    mae_after: float


@dataclass(frozen=True, eq=False)
class Diagnosis:
    """
    What the workflow found.

    Parameters
    ----------
    effect : str
        The first (and largest) effect named, or ``none``.
    model : JointModel
        The model with every kept effect.
    ledger : tuple[LedgerStep, ...]
        The effects added in turn, with the validation MAE before and after each.
    candidates : tuple[Candidate, ...]
        Every effect tried in the first iteration, ranked.
    rounds : tuple[tuple[Candidate, ...], ...]
        The candidates of every iteration.
    mae_before : float
        Validation MAE of the model given, degrees.
    mae_after : float
        Validation MAE of the final model, degrees.

    """

    effect: str
    model: JointModel
    ledger: tuple[LedgerStep, ...]
    candidates: tuple[Candidate, ...]
    rounds: tuple[tuple[Candidate, ...], ...]
    mae_before: float
    mae_after: float


@dataclass(frozen=True, eq=False)
class _Run:
    record: Record
    dt: float
    start: int


def _settled_start(record: Record, hold: int, fallback: int) -> int:
    """First sample after the command has stayed the same for ``hold`` samples."""
    changes = np.flatnonzero(np.diff(record.v)) + 1
    starts = np.r_[0, changes]
    ends = np.r_[changes, record.v.size]
    long = np.flatnonzero(ends - starts > hold)
    if long.size == 0:
        return fallback
    return min(int(starts[long[0]]) + hold, record.v.size - 2)


def simulate_record(model: JointModel, run: _Run, backlash_offset: float = 0.0) -> FloatArray:
    """Simulate a record from the first sample at which the joint's state is settled."""
    record = run.record
    return simulate(model, record.v, run.dt, float(record.y[run.start]),
                    v_before=float(record.v[run.start]), start=run.start,
                    backlash_offset=backlash_offset)


def _record_mae(model: JointModel, run: _Run) -> float:
    # Valve lag and delay are settled at the start; the side the play was taken up on is
    # not known, so the best of the three play states is used.
    play = model.effect(Backlash.name)
    half = 0.5 * play.play if isinstance(play, Backlash) else 0.0
    offsets = (0.0, -half, half) if half > 0.0 else (0.0,)
    measured = run.record.y[run.start:]
    return min(float(np.mean(np.abs(measured - simulate_record(model, run, o)[run.start:])))
               for o in offsets)


def mae(model: JointModel, runs: Sequence[_Run]) -> float:
    """Return the mean absolute simulation error over runs, degrees."""
    weights = [len(run.record) - run.start for run in runs]
    return float(np.average([_record_mae(model, run) for run in runs], weights=weights))


def velocity_residuals(model: JointModel, runs: Sequence[_Run]) -> list[FloatArray]:
    """Return ``dy - dy^`` per run: measured increments against one-step predictions."""
    out = []
    for run in runs:
        record = run.record
        predicted = one_step_increments(model, record.v, record.y, run.dt, start=run.start,
                                        v_before=float(record.v[0]))
        out.append(np.diff(record.y[run.start:]) - predicted)
    return out


def _blocks(residuals: Sequence[FloatArray], size: int) -> FloatArray:
    sums = []
    for series in residuals:
        squared = series * series
        whole = squared.size // size
        if whole:
            sums.append(squared[:whole * size].reshape(whole, size).sum(axis=1))
    return np.concatenate(sums) if sums else np.zeros(0)


def compare(base: list[FloatArray], candidate: list[FloatArray], size: int) -> tuple[float, float]:
    """
    Share of the squared residual removed, and its block-paired t statistic.

    Parameters
    ----------
    base, candidate : list of FloatArray
        Velocity residuals of the two models, run by run.
    size : int
        Samples per block.

    Returns
    -------
    tuple[float, float]
        ``(gain, t)``.

    """
    before, after = _blocks(base, size), _blocks(candidate, size)
    if before.size < 3:
        return 0.0, 0.0
    difference = before - after
    spread = float(np.std(difference, ddof=1))
    t = float(np.mean(difference) / (spread / math.sqrt(difference.size))) if spread > 0 \
        else (math.inf if np.mean(difference) > 0 else 0.0)
    return float(1.0 - after.sum() / before.sum()), t


def _features(static_map) -> tuple[bool, bool, bool]:
    """Return (dead-zone, saturation, asymmetric) of a map."""
    if isinstance(static_map, LinearMap):
        return False, False, False
    if isinstance(static_map, SdpDzMap):
        low, high = static_map.dead_zone
        same = math.isclose(static_map.slope[0], static_map.slope[1], rel_tol=1e-6)
        return high > low, False, not same
    if isinstance(static_map, SdpMap):
        low, high = static_map.dead_zone
        vn, vp = static_map.saturation_velocity
        cn, cp = static_map.curvature
        symmetric = math.isclose(-vn, vp, rel_tol=1e-6) and math.isclose(cn, cp, rel_tol=1e-6)
        return high > low, True, not symmetric
    return True, True, True


class _MapFamily:
    """Static maps with a chosen set of features, fitted by regret-regression."""

    def __init__(self, dead_zone: bool, saturation: bool, asymmetric: bool, rest: float,
                 scale: float) -> None:
        self.dead_zone, self.saturation, self.asymmetric = dead_zone, saturation, asymmetric
        self.rest, self.scale = rest, scale

    def unpack(self, x: FloatArray):
        """Return (low, high, speeds or slopes, curvatures) from free parameters."""
        i = 0
        if self.dead_zone:
            # Edges stay inside the commands seen (a runaway edge explains nothing).
            low = self.rest - min(math.exp(min(x[0], 50.0)), self.scale)
            high = self.rest + min(math.exp(min(x[1], 50.0)), self.scale)
            i = 2
        else:
            low = high = self.rest
        x = np.clip(x, -50.0, 50.0)
        if self.asymmetric:
            a, b = math.exp(x[i]), math.exp(x[i + 1])
            i += 2
        else:
            a = b = math.exp(x[i])
            i += 1
        if self.saturation:
            if self.asymmetric:
                cn, cp = math.exp(x[i]), math.exp(x[i + 1])
            else:
                cn = cp = math.exp(x[i])
            return low, high, (a, b), (cn, cp)
        return low, high, (a, b), None

    def build(self, x: FloatArray):
        """Return the map for free parameters ``x``."""
        low, high, (a, b), curvature = self.unpack(x)
        if curvature is None:
            return SdpDzMap(dead_zone=(low, high), slope=(a, b))
        return SdpMap(dead_zone=(low, high), saturation_velocity=(-a, b), curvature=curvature)

    def start(self, static_map) -> FloatArray:
        """Free parameters near ``static_map`` (any kind), for a fit to start from."""
        v = np.linspace(self.rest - self.scale, self.rest + self.scale, 41)
        speeds = static_map.rate(v)
        edge = 0.05 * self.scale
        x = []
        if self.dead_zone:
            low, high = (static_map.dead_zone if getattr(static_map, 'dead_zone', None)
                         and static_map.dead_zone[1] > static_map.dead_zone[0]
                         else (self.rest - edge, self.rest + edge))
            x += [math.log(max(self.rest - low, 1e-3 * self.scale)),
                  math.log(max(high - self.rest, 1e-3 * self.scale))]
        top = max(abs(speeds[0]), 1e-6), max(abs(speeds[-1]), 1e-6)
        if self.saturation:
            sizes = [1.2 * top[0], 1.2 * top[1]]
            curvature = [2.0 / self.scale] * 2
            if isinstance(static_map, SdpMap):
                sizes = [-static_map.saturation_velocity[0], static_map.saturation_velocity[1]]
                curvature = list(static_map.curvature)
        else:
            sizes = [top[0] / self.scale, top[1] / self.scale]
            curvature = None
            if isinstance(static_map, SdpDzMap):
                sizes = list(static_map.slope)
        x += [math.log(sizes[0]), math.log(sizes[1])] if self.asymmetric else \
            [math.log(0.5 * (sizes[0] + sizes[1]))]
        if curvature is not None:
            x += [math.log(curvature[0]), math.log(curvature[1])] if self.asymmetric else \
                [math.log(0.5 * (curvature[0] + curvature[1]))]
        return np.array(x)


def _fit_family(model: JointModel, family: _MapFamily, data: FitData):
    x0 = family.start(model.static_map)

    def residuals(p):
        return data.residuals(family.build(p[:-1]).rate, 1.0 / (1.0 + math.exp(-p[-1])))
    result = least_squares(residuals, np.r_[x0, 0.0], method='lm')
    return family.build(result.x[:-1])


class _Context:
    """Data shared by the candidates of one iteration."""

    def __init__(self, model: JointModel, runs: Sequence[_Run], max_delay: int) -> None:
        self.model = model
        self.runs = runs
        self.dt = runs[0].dt
        self.max_delay = max_delay
        self.block = max(2, int(round(BLOCK_SECONDS / self.dt)))
        self.base = velocity_residuals(model, runs)
        self.segmentation = segment_records([r.record for r in runs], max_delay=max_delay)
        levels = np.concatenate([r.record.v for r in runs])
        self.rest = rest_command(model) if model.dead_zone is not None else \
            self.segmentation.rest
        self.scale = max(float(np.max(np.abs(levels - self.rest))), 1e-9)

    def fit_data(self, delay: int) -> FitData:
        pieces = split_long(self.segmentation.experiments, 3000, self.max_delay)
        return FitData(thin(pieces, 60_000), delay, self.dt)

    def score(self, effect: str, candidate: JointModel, parameters: dict,
              evidence: str) -> tuple[Candidate, JointModel]:
        gain, t = compare(self.base, velocity_residuals(candidate, self.runs), self.block)
        significant = t > T_LIMIT and gain > MIN_GAIN
        return Candidate(effect, True, gain, t, significant, parameters, evidence), candidate


def _refit_map(context: _Context, features: tuple[bool, bool, bool],
               delay: float | None = None) -> JointModel:
    model = context.model if delay is None else replace(context.model, delay=delay)
    samples = model.delay_samples(context.dt)
    data = context.fit_data(samples)
    if all(features):
        # The full eq. (5) map: identify's multi-start fit, started from the data's speeds.
        points = level_speeds(data.experiments, samples, context.dt, rest=context.rest)
        return replace(model, static_map=fit_sdp(data, points, context.rest).static_map)
    family = _MapFamily(*features, rest=context.rest, scale=context.scale)
    return replace(model, static_map=_fit_family(model, family, data))


def _map_parameters(model: JointModel) -> dict:
    return dict(model.static_map.to_mapping())


def _try_dead_zone(context: _Context):
    features = _features(context.model.static_map)
    candidate = _refit_map(context, (True, features[1], features[2]))
    low, high = candidate.dead_zone
    return context.score('dead_zone', candidate, _map_parameters(candidate),
                         f'the joint stays still for commands in [{low:.4g}, {high:.4g}] '
                         'where the model moves it')


def _try_saturation(context: _Context):
    features = _features(context.model.static_map)
    if features[1]:
        return Candidate('velocity_saturation', False), None
    candidate = _refit_map(context, (features[0], True, features[2]))
    speeds = candidate.static_map.saturation_velocity
    return context.score('velocity_saturation', candidate, _map_parameters(candidate),
                         f'the speed levels off at {speeds[0]:.3g} and {speeds[1]:.3g} deg/s '
                         'while the model keeps growing with the command')


def _try_asymmetry(context: _Context):
    features = _features(context.model.static_map)
    if features[2]:
        return Candidate('asymmetry', False), None
    candidate = _refit_map(context, (features[0], features[1], True))
    return context.score('asymmetry', candidate, _map_parameters(candidate),
                         'the two directions move at different speeds for the same command '
                         'size')


def _try_time_delay(context: _Context):
    experiments = thin(context.segmentation.experiments, 100_000)
    estimate = estimate_delay(experiments, context.dt, max_delay=context.max_delay,
                              rest=context.segmentation.rest,
                              noise=context.segmentation.noise_std)
    current = context.model.delay_samples(context.dt)
    if estimate.samples == current:
        return Candidate('time_delay', True, evidence=f'the data agree with the delay of '
                         f'{current} samples'), None
    delay = round(estimate.samples * context.dt, 9)
    candidate = replace(context.model, delay=delay)
    return context.score('time_delay', candidate, {'delay': delay},
                         f'speed changes follow command changes after {estimate.samples} '
                         f'samples, not {current} (cross-correlation {estimate.xcorr})')


def _try_direction_delay(context: _Context):
    current = context.model.delay_samples(context.dt)
    best = None
    span = range(max(1, current - 10), current + 11)
    base = _blocks(context.base, context.block).sum()
    for positive in span:
        for negative in span:
            if positive == negative:
                continue
            effect = DirectionDependentDelay(positive * context.dt, negative * context.dt)
            candidate = context.model.with_effect(effect)
            total = _blocks(velocity_residuals(candidate, context.runs), context.block).sum()
            if best is None or total < best[0]:
                best = (total, positive, negative)
    if best is None or best[0] >= base:
        return Candidate('direction_dependent_delay', True), None
    _, positive, negative = best
    effect = DirectionDependentDelay(round(positive * context.dt, 9),
                                     round(negative * context.dt, 9))
    return context.score('direction_dependent_delay', context.model.with_effect(effect),
                         {'positive': effect.positive, 'negative': effect.negative},
                         f'motion in the positive direction starts {positive} samples after '
                         f'its command, in the negative direction {negative}')


def _try_angle_limits(context: _Context):
    low, high = context.segmentation.end_stops
    if low is None and high is None:
        return Candidate('angle_limits', True, evidence='the joint is never held still while '
                         'driven'), None
    angles = np.concatenate([r.record.y for r in context.runs])
    low = float(np.min(angles)) - 1e-6 if low is None else low
    high = float(np.max(angles)) + 1e-6 if high is None else high
    if context.model.angle_limits is not None and \
            np.allclose(context.model.angle_limits, (low, high), atol=0.1):
        return Candidate('angle_limits', True), None
    candidate = replace(context.model, angle_limits=(low, high))
    return context.score('angle_limits', candidate, {'angle_limits': [low, high]},
                         f'the joint is held still at {low:.3g} and {high:.3g} deg although '
                         'the command drives it on')


def _fit_scalar(context: _Context, build: Callable[[float], JointModel],
                bounds: tuple[float, float], log: bool = False) -> float:
    def cost(x):
        value = math.exp(x) if log else x
        return float(_blocks(velocity_residuals(build(value), context.runs),
                             context.block).sum())
    low, high = (math.log(bounds[0]), math.log(bounds[1])) if log else bounds
    result = minimize_scalar(cost, bounds=(low, high), method='bounded',
                             options={'xatol': 1e-3})
    return math.exp(result.x) if log else float(result.x)


def _try_valve_lag(context: _Context):
    if context.model.effect(ValveLag.name) is not None:
        return Candidate('valve_lag', False), None
    constant = _fit_scalar(context, lambda T: context.model.with_effect(ValveLag(T)),
                           (0.2 * context.dt, 2.0), log=True)
    candidate = context.model.with_effect(ValveLag(constant))
    return context.score('valve_lag', candidate, {'time_constant': constant},
                         f'after each command change the speed settles with a time constant '
                         f'of {constant:.3g} s')


def _try_backlash(context: _Context):
    if context.model.effect(Backlash.name) is not None:
        return Candidate('backlash', False), None
    play = _fit_scalar(context, lambda b: context.model.with_effect(Backlash(b)), (0.0, 10.0))
    candidate = context.model.with_effect(Backlash(play))
    return context.score('backlash', candidate, {'play': play},
                         f'after each reversal the angle stands still while {play:.3g} deg of '
                         'play are taken up')


def _try_angle_velocity(context: _Context):
    if context.model.effect(AngleDependentVelocity.name) is not None:
        return Candidate('angle_dependent_velocity', False), None
    # eps ~ dt |w| (A cos y + B sin y) with A = c cos(phi), B = -c sin(phi): a linear
    # regression of the velocity residual on the model speed times the angle's cosine and
    # sine (the library term 'q cos(y) sgn(q)' of docs/methods.md 8.6) gives c and phi at once.
    rows, targets = [], []
    for run, residual in zip(context.runs, context.base):
        record = run.record
        speed = run.dt * np.abs(speed_profile(context.model, record.v, run.dt,
                                              v_before=float(record.v[0]))[run.start + 1:])
        angle = np.radians(record.y[run.start:-1])
        rows.append(np.column_stack([speed * np.cos(angle), speed * np.sin(angle)]))
        targets.append(residual)
    a, b = np.linalg.lstsq(np.concatenate(rows), np.concatenate(targets), rcond=None)[0]

    def effect_of(p: FloatArray) -> AngleDependentVelocity:
        return AngleDependentVelocity(min(math.hypot(p[0], p[1]), 0.95),
                                      math.degrees(math.atan2(-p[1], p[0])) % 360.0)

    # Polish on the exact one-step residuals (the regression ignores the end stops).
    result = least_squares(lambda p: np.concatenate(velocity_residuals(
        context.model.with_effect(effect_of(p)), context.runs)), np.array([a, b]),
        method='lm', max_nfev=100)
    effect = effect_of(result.x)
    amplitude, phase = effect.amplitude, effect.phase
    candidate = context.model.with_effect(effect)
    return context.score('angle_dependent_velocity', candidate,
                         {'amplitude': amplitude, 'phase': phase},
                         f'the speed for a given command changes with the angle by '
                         f'{100 * amplitude:.3g} % (phase {phase:.3g} deg)')


DETECTORS = {
    'dead_zone': _try_dead_zone, 'velocity_saturation': _try_saturation,
    'asymmetry': _try_asymmetry, 'time_delay': _try_time_delay,
    'direction_dependent_delay': _try_direction_delay, 'angle_limits': _try_angle_limits,
    'valve_lag': _try_valve_lag, 'backlash': _try_backlash,
    'angle_dependent_velocity': _try_angle_velocity,
}


def runs_of(records: Sequence[Record], model: JointModel, max_delay: float) -> list[_Run]:
    """
    Wrap records with the sample each is simulated from.

    That is the first sample after the command has been held long enough for every
    delay considered and for a valve lag to settle (1 s at least).
    """
    runs = []
    for record in records:
        dt = check_record(record)
        hold = int(round(max(1.0, max_delay) / dt))
        fallback = min(int(round(max_delay / dt)) + 1, len(record) - 2)
        runs.append(_Run(record, dt, _settled_start(record, hold, fallback)))
    return runs


def diagnose(records: Sequence[Record], model: JointModel, *,
             validation: Sequence[Record] | None = None, max_iterations: int = 4,
             max_delay: float = 0.5,
             progress: Callable[[str], None] | None = None) -> Diagnosis:
    """
    Name what the model misses, add it, and repeat until nothing significant is left.

    Parameters
    ----------
    records : sequence of Record
        Measured records of the joint (estimation data).
    model : JointModel
        The model to hold against them.
    validation : sequence of Record or None
        Held-out records for the MAE before and after (default: the estimation records).
    max_iterations : int
        Most effects added.
    max_delay : float
        Largest delay considered, s.
    progress : callable or None
        Called with a description of each step.

    Returns
    -------
    Diagnosis
        The named effect, the ledger, the candidates and the augmented model.

    """
    if not records:
        raise DataError('no records to diagnose')
    runs = runs_of(records, model, max_delay)
    checks = runs_of(validation, model, max_delay) if validation else runs
    dt = runs[0].dt
    horizon = max(2, int(round(max_delay / dt)))
    before = mae(model, checks)
    current, current_mae = model, before
    ledger: list[LedgerStep] = []
    rounds: list[tuple[Candidate, ...]] = []
    for _ in range(max_iterations):
        context = _Context(current, runs, horizon)
        results = []
        for effect, detector in DETECTORS.items():
            if progress is not None:
                progress(effect)
            try:
                results.append(detector(context))
            except (HydroSdpError, np.linalg.LinAlgError, ValueError) as error:
                results.append((Candidate(effect, False, evidence=f'could not be fitted: '
                                          f'{error}'), None))
        ranked = sorted(results, key=lambda item: (not item[0].significant, -item[0].gain))
        rounds.append(tuple(candidate for candidate, _ in ranked))
        chosen = None
        for candidate, augmented in ranked:
            if not candidate.significant or augmented is None:
                break
            after = mae(augmented, checks)
            if after < current_mae:
                chosen = (candidate, augmented, after)
                break
        if chosen is None:
            break
        candidate, current, after = chosen
        ledger.append(LedgerStep(candidate.effect, candidate.parameters, current_mae, after))
        current_mae = after
    return Diagnosis(effect=ledger[0].effect if ledger else 'none', model=current,
                     ledger=tuple(ledger), candidates=rounds[0] if rounds else (),
                     rounds=tuple(rounds), mae_before=before, mae_after=current_mae)

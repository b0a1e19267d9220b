"""Model evaluation as in Table 2 of West et al. (2018) (methods 3.8, 13.6)."""

from __future__ import annotations

from dataclasses import dataclass, replace
import math
from typing import Sequence

from hydro_sdp.core.arrays import FloatArray
from hydro_sdp.core.identification.segmentation import check_record
from hydro_sdp.core.identification.stalls import pieces_between, stalled
from hydro_sdp.core.model.effects import Backlash, ValveLag
from hydro_sdp.core.model.exogenous_signals import Exogenous, exogenous_of
from hydro_sdp.core.model.joint_model import JointModel
from hydro_sdp.core.model.records import Record
from hydro_sdp.core.model.simulation import simulate
from hydro_sdp.core.model.static_maps import (
    chord_commands, CHORD_SPEED_FRACTION, linearise, LinearMap, PwlMap, SdpDzMap, SdpMap)
from hydro_sdp.core.model.timing import SamplePeriod
import numpy as np
from scipy.optimize import minimize_scalar


@dataclass(frozen=True)
class RecordScore:
    """
    Errors of the three models on one record.

    Attributes
    ----------
    source : str
        The record's origin.
    model : float
        MAE of the model, degrees.
    sdp_dz : float
        MAE of its SDP-DZ linearisation (NaN when the map has no dead-zone form).
    linear : float
        MAE of the linear model with its best gain.
    linear_gain : float
        That gain, deg/s per input unit.
    stalled : float
        Time the joint stalled and that is left out of the scores, s (:mod:`.stalls`).

    """

    source: str
    samples: int
    model: float
    sdp_dz: float
    linear: float
    linear_gain: float
    stalled: float = 0.0


def sdp_dz_benchmark(model: JointModel) -> JointModel | None:
    """Return the SDP-DZ linearisation of a model, or None if its map has no dead-zone form."""
    static_map = model.static_map
    if isinstance(static_map, SdpMap):
        chord = linearise(static_map, *chord_commands(static_map))
    elif isinstance(static_map, SdpDzMap):
        chord = static_map
    elif isinstance(static_map, PwlMap) and static_map.dead_zone is not None:
        low, high = static_map.dead_zone
        knots, speeds = np.array(static_map.knots), np.array(static_map.speeds)
        slopes = []
        for edge, end, sign in ((low, speeds[0], -1.0), (high, speeds[-1], 1.0)):
            target = CHORD_SPEED_FRACTION * end
            side = knots < low if sign < 0 else knots > high
            if not side.any() or end == 0.0:
                return None
            # Where the map reaches two thirds of its end speed, by interpolation.
            order = np.argsort(np.abs(speeds[side]))
            command = float(np.interp(abs(target), np.abs(speeds[side])[order],
                                      knots[side][order]))
            slopes.append(target / (command - edge))
        chord = SdpDzMap(dead_zone=(low, high), slope=(slopes[0], slopes[1]))
    else:
        return None
    return replace(model, static_map=chord, effects=())


#: A valve lag's unknown state at a record's start is forgotten after this many of its
#: time constants (e^-5: under 1 %).
LAG_MEMORY = 5.0


def first_compared(model: JointModel, dt: SamplePeriod, record: Record) -> int:
    """
    Return the first sample compared: where the model's state no longer depends on the past.

    The reasoning is in docs/methods.md section 3.8.

    """
    known = model.longest_delay_samples(dt)
    lag = model.effect(ValveLag.name)
    if isinstance(lag, ValveLag):
        known += int(math.ceil(LAG_MEMORY * lag.time_constant / dt))
    return min(known, len(record) - 2)


def _simulated(model: JointModel, record: Record, dt: SamplePeriod, start: int,
               exogenous: Exogenous | None = None, backlash_offset: float = 0.0) -> FloatArray:
    return simulate(model, record.v, dt, float(record.y[start]), v_before=float(record.v[0]),
                    start=start, backlash_offset=backlash_offset,
                    exogenous=exogenous if exogenous is not None else exogenous_of(record, dt))


def _mae(model: JointModel, record: Record, dt: SamplePeriod, start: int) -> float:
    simulated = _simulated(model, record, dt, start)
    return float(np.mean(np.abs(record.y[start:] - simulated[start:])))


def simulated_record(model: JointModel, record: Record, dt: SamplePeriod | None = None,
                     exogenous: Exogenous | None = None) -> tuple[int, FloatArray]:
    """
    Simulate a model over a record as every figure of its error does (methods 3.8).

    ``dt``: its sample period, s (default: checked from the record).
    ``exogenous``: its load and other joints' speeds, if already built.
    Returns: the first sample compared, and the simulated angles (degrees; before that sample they
    repeat it).
    """
    dt = check_record(record, min_samples=2) if dt is None else dt
    start = first_compared(model, dt, record)
    play = model.effect(Backlash.name)
    half = 0.5 * play.play if isinstance(play, Backlash) else 0.0
    offsets = (0.0, -half, half) if half > 0.0 else (0.0,)
    simulations = [_simulated(model, record, dt, start, exogenous, offset) for offset in offsets]
    errors = [float(np.mean(np.abs(record.y[start:] - s[start:]))) for s in simulations]
    return start, simulations[int(np.argmin(errors))]


def record_mae(model: JointModel, record: Record, dt: SamplePeriod | None = None,
               exogenous: Exogenous | None = None,
               left_out: np.ndarray | None = None) -> float:
    """
    Return the model's mean absolute simulation error over one record, degrees.

    The one figure ``evaluate``, ``diagnose`` and ``calibrate`` report, over the
    simulation of :func:`simulated_record`.

    ``dt``: its sample period, s (default: checked from the record).
    ``exogenous``: its load and other joints' speeds, if already built.
    ``left_out``: samples not scored (a stall): the simulation starts again from the measured angle
    after each such stretch.
    Returns: the MAE, degrees.
    """
    start, simulated = simulated_record(model, record, dt, exogenous)
    if left_out is None or not np.any(left_out[start:]):
        return float(np.mean(np.abs(record.y[start:] - simulated[start:])))
    dt = check_record(record, min_samples=2) if dt is None else dt
    total, count = 0.0, 0
    for first, end in pieces_between(left_out, start):
        again = simulated if first == start else _simulated(model, record, dt, first, exogenous)
        total += float(np.sum(np.abs(record.y[first:end] - again[first:end])))
        count += end - first
    return total / count if count else math.nan


def best_linear_gain(record: Record, model: JointModel, dt: SamplePeriod) -> tuple[float, float]:
    """
    Gain of eq. (2) that minimises the record's MAE, and that MAE.

    ``dt``: sample period, s.
    Returns: ``(gain, mae)``; gain in deg/s per input unit.
    """
    linear = JointModel(model.joint, LinearMap(1.0), model.delay)
    tau = model.delay_samples(dt)
    start = first_compared(model, dt, record)
    delayed = np.r_[np.full(tau, record.v[0]), record.v[:-tau]][start:]
    integrated = dt * np.cumsum(np.r_[0.0, delayed[1:]])
    rise = record.y[start:] - record.y[start]
    denominator = float(np.dot(integrated, integrated))
    guess = abs(float(np.dot(integrated, rise)) / denominator) if denominator > 0 else 1.0
    guess = max(guess, 1e-9)

    def cost(log_gain: float) -> float:
        return _mae(replace(linear, static_map=LinearMap(math.exp(log_gain))), record, dt,
                    start)

    result = minimize_scalar(cost, bounds=(math.log(guess) - 5.0, math.log(guess) + 5.0),
                             method='bounded', options={'xatol': 1e-4})
    return math.exp(result.x), float(result.fun)


def evaluate(records: Sequence[Record], model: JointModel) -> list[RecordScore]:
    """
    Table-2 comparison of a model with its SDP-DZ and linear benchmarks.

    Parameters
    ----------
    records : sequence of Record
        Evaluation records (random-level runs in the paper).
    model : JointModel
        The model to evaluate.

    Returns
    -------
    list of RecordScore
        One row per record.

    See Also
    --------
    identify : the model to evaluate.
    simulate : the simulation each score compares.

    Examples
    --------
    >>> import numpy as np
    >>> from hydro_sdp import evaluate, load_model, Record, simulate
    >>> model = load_model('config/brokk_j2.yaml')
    >>> t = np.arange(0.0, 5.0, 0.01)
    >>> v = np.where(t < 1.0, 0.0, 4.0)
    >>> scores = evaluate([Record(t, v, simulate(model, v, 0.01, 30.0), joint='j2')], model)
    >>> round(scores[0].model, 6)
    0.0

    """
    benchmark = sdp_dz_benchmark(model)
    scores = []
    travel = (min(float(np.min(r.y)) for r in records),
              max(float(np.max(r.y)) for r in records)) if records else None
    for record in records:
        dt = check_record(record, min_samples=2)
        start = first_compared(model, dt, record)
        gain, linear = best_linear_gain(record, model, dt)
        # A stall is the load's, not the valve's: left out, and said.
        left_out = stalled(model, record, dt, travel)
        scores.append(RecordScore(
            source=record.source, samples=len(record) - start - int(np.sum(left_out[start:])),
            model=record_mae(model, record, dt, left_out=left_out),
            sdp_dz=record_mae(benchmark, record, dt, left_out=left_out)
            if benchmark is not None else math.nan,
            linear=linear, linear_gain=gain, stalled=float(np.sum(left_out)) * dt))
    return scores


def simulated_angles(model: JointModel, record: Record) -> FloatArray:
    """Simulate ``model`` over a record as :func:`evaluate` does (for plots)."""
    return simulated_record(model, record)[1]


#: The two ways :func:`mean_errors` averages, by name.
AVERAGES = {'per_record': 'mean over records, each counted once (Table 2)',
            'time_weighted': 'mean over all compared samples (records weighted by length)'}


def mean_errors(scores: Sequence[RecordScore]) -> dict[str, dict[str, float]]:
    """
    Average each model's MAE per record and weighted by time.

    ``scores``: one per record, from :func:`evaluate`.
    Returns: ``{'per_record': {...}, 'time_weighted': {...}}``, each mapping ``model``, ``sdp_dz``
    and ``linear`` to degrees (NaN where undefined).
    """
    weights = np.array([s.samples for s in scores], dtype=np.float64)
    out: dict[str, dict[str, float]] = {'per_record': {}, 'time_weighted': {}}
    for key in ('model', 'sdp_dz', 'linear'):
        values = np.array([getattr(s, key) for s in scores], dtype=np.float64)
        out['per_record'][key] = float(np.mean(values)) if values.size else math.nan
        out['time_weighted'][key] = float(np.sum(weights * values) / np.sum(weights)) \
            if values.size and np.sum(weights) > 0 else math.nan
    return out

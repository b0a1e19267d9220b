"""
Detectors of effects seen only in signals beyond the joint's own: flow sharing, load.

Both need what a record may carry besides its command and angle
(:class:`~hydro_sdp.core.model.records.Record` ``others`` and ``load``); on records
without it they are not applicable, with the reason as evidence.

* ``flow_sharing``: the joint slows when another joint moves at the same time
  (one pump for both). Fitted as a shared pump-flow limit
  (:class:`~hydro_sdp.core.model.effects.FlowSharing`).
* ``load_dependence``: the speed changes with the load. With a measured load,
  an overrunning load (the squared speed factor growing with the load beyond an
  onset, fitted on the one-step increments) or a relative speed change per load
  unit in each direction, whichever is significant with the larger gain;
  without one, a speed scale per record and direction, named only when the
  records' scales at the same command differ beyond their noise (a chi-square
  test of heterogeneity on block-robust standard errors).

"""

from __future__ import annotations

from dataclasses import dataclass
import math
from typing import Any

from hydro_sdp.core.arrays import FloatArray
from hydro_sdp.core.diagnosis.context import Context
from hydro_sdp.core.diagnosis.detectors.base import EffectDetector
from hydro_sdp.core.diagnosis.detectors.overrun import (
    fit_overrun, inner_range, one_step_samples)
from hydro_sdp.core.diagnosis.residuals import mae, Run
from hydro_sdp.core.diagnosis.results import Candidate, Trial
from hydro_sdp.core.model.effects import FlowSharing, LoadDependence
from hydro_sdp.core.model.exogenous_signals import record_key, summed_other_speeds
from hydro_sdp.core.model.joint_model import JointModel
from hydro_sdp.core.model.simulation import one_step_increments
from hydro_sdp.core.model.timing import delayed_at
import numpy as np
from scipy.optimize import least_squares, minimize, minimize_scalar
from scipy.stats import chi2

#: Heterogeneity of the per-record scales is named below this p-value.
P_LIMIT = 1e-3
#: ...and when the scales at one command differ by at least this share.
MIN_SPREAD = 0.03
#: Share of the angle range at either end left out of the per-record scales.
END_SHARE = 0.1


def other_speed_sums(context: Context) -> list[FloatArray | None]:
    """Return the summed other joints' speed per residual sample of each run, deg/s."""
    return [summed_other_speeds(run.exogenous, run.start) for run in context.runs]


def _predicted(context: Context) -> list[FloatArray]:
    """One-step increments of the model under test, per run, deg."""
    return [one_step_increments(context.model, run.record.v, run.record.y, run.dt,
                                start=run.start, v_before=float(run.record.v[0]),
                                exogenous=run.exogenous)
            for run in context.runs]


class FlowSharingDetector(EffectDetector):
    """The joint slows while other joints move: fit a shared pump-flow limit."""

    word = 'flow_sharing'
    description = 'the joint slows while other joints move (one pump)'
    remedy = 'effect, pump-flow limit fitted'
    feature = 'others'

    def fit_effect(self, context: Context) -> Trial:
        """Fit the limit and the other joints' full speeds, and score them."""
        sums = other_speed_sums(context)
        if all(s is None for s in sums):
            return Candidate(self.word, False, evidence='the records carry no other joints '
                             '(JointState of one joint)'), None
        moving = np.concatenate([s for s in sums if s is not None])
        top = float(np.quantile(moving, 0.99)) if moving.size else 0.0
        if not top > 1.0:
            return Candidate(self.word, False, evidence='the other joints never move '
                             f'(summed speed below {max(top, 0.0):.2g} deg/s)'), None
        levels = np.unique(np.concatenate([r.record.v for r in context.runs]))
        rates = context.model.rate(levels)
        # Full demand: the top speed in each direction, where the joint alone takes the pump.
        full = (float(np.max(rates)), float(-np.min(rates)))
        if not min(full) > 0.0:
            return Candidate(self.word, False, evidence='the model does not move both ways '
                             'at the commands recorded'), None

        def model_with(p: FloatArray) -> JointModel:
            limit, up, down = np.exp(np.clip(p, -6.0, 6.0)).tolist()
            return context.model.with_effect(FlowSharing(limit, *full, top * up, top * down))

        def simulation_error(p: FloatArray) -> float:
            return mae(model_with(p), context.runs)
        # Fitted on the simulation error: the share a joint loses adds up over a move,
        # which the one-step residual weighs too little against the valve's transients.
        # The error is flat where the factor is 1: start from the best of a grid.
        grid = [np.log([limit, up, down]) for limit in (0.8, 1.1, 1.6)
                for up in (0.5, 1.0, 2.0) for down in (0.5, 1.0, 2.0)]
        # The error surface is rough (a share cut integrates into a drift): polish the
        # best two starts of the grid and keep the better.
        starts = sorted(grid, key=simulation_error)[:2]
        fits = [minimize(simulation_error, start, method='Nelder-Mead',
                         options={'xatol': 1e-3, 'fatol': 1e-6, 'maxfev': 120})
                for start in starts]
        best = min(fits, key=lambda fit: float(fit.fun)).x
        best = np.clip(best, -6.0, 6.0)
        augmented = model_with(best)
        effect = augmented.effect(self.word)
        assert isinstance(effect, FlowSharing)
        both = effect.limit / (1.0 + top / max(effect.other_positive, effect.other_negative))
        return context.score(
            self.word, augmented, {'limit': effect.limit, 'full_positive': effect.full_positive,
                                   'full_negative': effect.full_negative,
                                   'other_positive': effect.other_positive,
                                   'other_negative': effect.other_negative},
            f'while the other joints move ({top:.3g} deg/s) the speed at full command drops '
            f'to x{min(both, 1.0):.2f} or less (pump limit {effect.limit:.3g} full demands)')


def block_scale(measured: FloatArray, predicted: FloatArray, block: int) -> tuple[float, float]:
    """
    Scale of the measured travel on the predicted travel, and its standard error.

    The scale is the ratio of the summed increments (the travel, in which the
    link's ringing cancels); its error is the block (cluster) sandwich estimate
    from the unexplained travel of each block of ``block`` samples, so that
    autocorrelation within a block does not shrink it.

    Returns
    -------
    tuple[float, float]
        ``(scale, error)``; ``(nan, inf)`` when the predicted travel vanishes.

    """
    travel = float(np.sum(predicted))
    if not abs(travel) > 0.0 or predicted.size < 2 * block:
        return math.nan, math.inf
    scale = float(np.sum(measured)) / travel
    terms = measured - scale * predicted
    whole = terms.size // block * block
    sums = np.r_[terms[:whole].reshape(-1, block).sum(axis=1), terms[whole:].sum()]
    return scale, max(float(math.sqrt(np.sum(sums * sums))) / abs(travel), 1e-12)


def _polish(context: Context, run: Run, key: str, up: float,
            down: float) -> tuple[float, float]:
    """
    Return a record's speed factors per direction, fitted to its simulation error.

    Each record's error depends on its own factors only; each direction is fitted
    in turn within +-50 % of the regression's scale (1 where the record does not
    move that way).
    """
    factors = [up if math.isfinite(up) and up > 0.0 else 1.0,
               down if math.isfinite(down) and down > 0.0 else 1.0]
    for side, scale in enumerate((up, down)):
        if not (math.isfinite(scale) and scale > 0.0):
            continue

        def error(x: float) -> float:
            trial = list(factors)
            trial[side] = x
            effect = LoadDependence(records=(key,), record_positive=(trial[0],),
                                    record_negative=(trial[1],))
            return mae(context.model.with_effect(effect), [run])
        factors[side] = float(minimize_scalar(error, bounds=(0.5 * scale, 1.5 * scale),
                                              method='bounded', options={'xatol': 1e-3}).x)
    return factors[0], factors[1]


@dataclass(frozen=True)
class RecordScales:
    """
    Each record's speed scale per direction, and whether they differ beyond noise.

    Parameters
    ----------
    scales, errors : dict[str, list[float]]
        Scale (measured over predicted travel away from the ends of the range) and
        its standard error per record, under ``positive`` and ``negative`` (NaN and
        inf where the record does not move that way).
    loads : dict[str, list[float]]
        Mean load over those samples per record (NaN without a load signal).
    statistic : float
        Chi-square of the records' scales about their weighted mean, summed over
        the command levels (and directions) that two records or more share.
    freedom : int
        Its degrees of freedom.
    spread : float
        Largest relative spread of the scales at one level.

    """

    scales: dict[str, list[float]]
    errors: dict[str, list[float]]
    loads: dict[str, list[float]]
    statistic: float
    freedom: int
    spread: float

    @property
    def p_value(self) -> float:
        """Probability of a chi-square this large if the records' scales were equal."""
        return float(chi2.sf(self.statistic, self.freedom)) if self.freedom else 1.0

    def evidence(self) -> dict[str, list[float | None]]:
        """Return the scales and errors per direction for the report (None where undefined)."""
        def listed(values: list[float]) -> list[float | None]:
            return [float(v) if math.isfinite(v) else None for v in values]
        return {f'{what}_{name}': listed(table[name])
                for what, table in (('scales', self.scales), ('errors', self.errors))
                for name in ('positive', 'negative')}

    def describe(self) -> str:
        """One line for the evidence."""
        return (f'per-record speed scales at the same command: chi2 {self.statistic:.3g} on '
                f'{self.freedom} degrees of freedom (p = {self.p_value:.2g}), spread '
                f'{100 * self.spread:.3g} %')


def record_scales(context: Context) -> RecordScales:
    """Return every record's speed scale per direction and the test of their agreement."""
    predicted = _predicted(context)
    scales: dict[str, list[float]] = {'positive': [], 'negative': []}
    errors: dict[str, list[float]] = {'positive': [], 'negative': []}
    loads: dict[str, list[float]] = {'positive': [], 'negative': []}
    groups: dict[tuple[int, int], list[tuple[float, float]]] = {}
    width = 0.05 * context.scale
    # The ends of the range (cushions, impacts on the stops) are left out of the scales.
    low, high = inner_range(context, END_SHARE)
    for run, p in zip(context.runs, predicted):
        measured = np.diff(run.record.y[run.start:])
        angle = run.record.y[run.start:-1]
        inner = (angle > low) & (angle < high)
        samples = np.arange(run.start + 1, len(run.record))
        command = delayed_at(run.record.v, samples, context.model.delay_samples(run.dt))
        load = run.record.load[run.start + 1:] if run.record.load is not None else None
        for sign, name in ((1.0, 'positive'), (-1.0, 'negative')):
            side = (np.sign(p) == sign) & inner
            scale, error = block_scale(measured[side], p[side], context.block)
            scales[name].append(scale)
            errors[name].append(error)
            loads[name].append(float(np.mean(load[side])) if load is not None and side.any()
                               else math.nan)
            # The same record's scale at each command level, for the comparison.
            bins = np.round(command[side] / width).astype(np.int64)
            for level in np.unique(bins).tolist():
                chosen = bins == level
                fit = block_scale(measured[side][chosen], p[side][chosen], context.block)
                if math.isfinite(fit[0]):
                    groups.setdefault((int(sign), level), []).append(fit)
    statistic, freedom, spread = 0.0, 0, 0.0
    for fits in groups.values():
        if len(fits) < 2:
            continue
        value = np.array([f[0] for f in fits])
        weight = 1.0 / np.array([f[1] for f in fits]) ** 2
        mean = float(np.sum(weight * value) / np.sum(weight))
        statistic += float(np.sum(weight * (value - mean) ** 2))
        freedom += len(fits) - 1
        spread = max(spread, float(np.ptp(value)) / max(abs(mean), 1e-9))
    return RecordScales(scales, errors, loads, statistic, freedom, spread)


def _first_significant(context: Context, word: str, models: list[JointModel],
                       parameters: list[dict[str, Any]], evidence: str) -> Trial:
    """Score the models in turn; return the first significant one (else the last)."""
    trial: Trial | None = None
    for model, values in zip(models, parameters):
        trial = context.score(word, model, values, evidence)
        if trial[0].significant:
            break
    assert trial is not None
    return trial


class LoadDependenceDetector(EffectDetector):
    """The speed changes with the load: per load unit, or per record when none is measured."""

    word = 'load_dependence'
    description = 'the speed changes with the load (payload, digging)'
    remedy = 'effect, overrunning or per load unit (measured load), or per record'
    feature = 'command'

    def fit_effect(self, context: Context) -> Trial:
        """Fit on the measured load when every record has one, else per record."""
        if len(context.runs) < 2:
            return Candidate(self.word, False, evidence='one record: nothing to compare its '
                             'speed with'), None
        found = record_scales(context)
        with_load = all(run.record.load is not None for run in context.runs)
        if found.freedom == 0 and not with_load:
            return Candidate(self.word, True, evidence='no two records hold the same command '
                             'in the same direction'), None
        if with_load:
            return self._fit_load(context, found)
        if found.p_value > P_LIMIT or found.spread < MIN_SPREAD:
            return Candidate(self.word, True, evidence=found.describe() + ': within noise'), None
        return self._fit_records(context, found)

    def _fit_load(self, context: Context, found: RecordScales) -> Trial:
        """
        Fit both forms on the measured load; return the significant one of larger gain.

        The overrunning load is fitted on the one-step increments, the residual the
        block test scores: a factor fitted to the simulation error alone can improve
        it on average over a stroke while it worsens the speed sample by sample.
        """
        samples = one_step_samples(context, END_SHARE)
        measured, predicted, load = (np.concatenate([part[i] for part in samples])
                                     for i in range(3))
        factors = [fit_overrun(measured[side], predicted[side], load[side])
                   for side in (predicted > 0.0, predicted < 0.0)]
        (up, up_onset), (down, down_onset) = factors
        trials = []
        if up or down:
            effect = LoadDependence(overrun_positive=up, overrun_negative=down,
                                    onset_positive=up_onset, onset_negative=down_onset)
            trials.append(context.score(
                self.word, context.model.with_effect(effect),
                {'overrun_positive': up, 'overrun_negative': down,
                 'onset_positive': up_onset, 'onset_negative': down_onset,
                 **found.evidence()},
                'an overrunning load speeds the joint up: the squared speed grows by '
                f'{up:+.3g} (positive) and {down:+.3g} (negative) per load unit beyond '
                f'{up_onset:.3g} and {down_onset:.3g}; {found.describe()}'))
        trials.append(self._fit_linear(context, found))
        return max(trials, key=lambda trial: (trial[0].significant, trial[0].gain))

    def _fit_linear(self, context: Context, found: RecordScales) -> Trial:
        """Fit ``1 + k (L - ref)`` per direction to the records' scales, polish, score."""
        values, errors, loads, sides = [], [], [], []
        for index, name in enumerate(('positive', 'negative')):
            for value, error, mean in zip(found.scales[name], found.errors[name],
                                          found.loads[name]):
                if math.isfinite(value) and math.isfinite(error) and math.isfinite(mean):
                    values.append(value)
                    errors.append(error)
                    loads.append(mean)
                    sides.append(index)
        load, scale = np.array(loads), np.array(values)
        spread = float(np.ptp(load)) if load.size else 0.0
        if not spread > 0.0:
            return Candidate(self.word, True, evidence='the load does not change between '
                             'records'), None
        side = np.array(sides)
        # Weighted by the scales' errors, floored so that no record weighs in alone.
        weight = 1.0 / np.maximum(np.array(errors), 0.02)

        def misfit(q: FloatArray) -> FloatArray:
            slope = np.where(side == 0, q[0], q[1])
            return weight * (scale - 1.0 - slope * (load - q[2] * spread) / spread)
        start = np.array([0.0, 0.0, float(np.min(load)) / spread])
        k = least_squares(misfit, start).x

        lowest = float(np.min(load))

        def model_with(q: FloatArray) -> JointModel:
            # The reference stays within the loads seen (beyond, 1 + k (L - ref) degenerates
            # into a constant factor).
            reference = min(max(float(q[2] * spread), lowest), lowest + spread)
            return context.model.with_effect(
                LoadDependence(float(q[0] / spread), float(q[1] / spread), reference))

        polished = minimize(lambda q: mae(model_with(q), context.runs), k, method='Nelder-Mead',
                            options={'xatol': 1e-4, 'fatol': 1e-6, 'maxfev': 120}).x
        # Polished on the simulation error, unless that loses the one-step significance.
        models = [model_with(polished), model_with(k)]
        parameters = []
        for model in models:
            effect = model.effect(self.word)
            assert isinstance(effect, LoadDependence)
            parameters.append({'positive': effect.positive, 'negative': effect.negative,
                               'reference': effect.reference, **found.evidence()})
        return _first_significant(
            context, self.word, models, parameters,
            f'the speed changes by {100 * k[0]:+.3g} % (positive) and {100 * k[1]:+.3g} % '
            f'(negative) over the load range {spread:.3g}; {found.describe()}')

    def _fit_records(self, context: Context, found: RecordScales) -> Trial:
        """Give each record its own scale per direction, polish, score."""
        keys = tuple(record_key(run.record) for run in context.runs)
        scales = found.scales
        travel = [(u if math.isfinite(u) else 1.0, d if math.isfinite(d) else 1.0)
                  for u, d in zip(scales['positive'], scales['negative'])]
        polished = [_polish(context, run, key, up, down) for run, key, up, down in
                    zip(context.runs, keys, scales['positive'], scales['negative'])]
        # The factors fitted to the simulation error, unless they no longer shrink the
        # one-step residual significantly (a record that rings or bounces): then the
        # travel ratios.
        models, parameters = [], []
        for factors in (polished, travel):
            up = tuple(f[0] for f in factors)
            down = tuple(f[1] for f in factors)
            models.append(context.model.with_effect(
                LoadDependence(records=keys, record_positive=up, record_negative=down)))
            parameters.append({'records': list(keys), 'record_positive': list(up),
                               'record_negative': list(down),
                               **found.evidence()})
        return _first_significant(context, self.word, models, parameters, found.describe())

"""Detector of a speed that changes with the load, `load_dependence` (methods 8.2, 8.4)."""

from __future__ import annotations

from dataclasses import replace
import math

from hydro_sdp.core.diagnosis.context import Context
from hydro_sdp.core.diagnosis.detectors.base import EffectDetector
from hydro_sdp.core.diagnosis.detectors.load_forms import best_sides
from hydro_sdp.core.diagnosis.detectors.load_shape import (
    describe, fitted_table, load_knots, sdp_table)
from hydro_sdp.core.diagnosis.detectors.overrun import fit_overrun, one_step_samples
from hydro_sdp.core.diagnosis.detectors.power_cap import fit_power_cap
from hydro_sdp.core.diagnosis.detectors.record_scales import (
    END_SHARE, first_significant, MIN_SPREAD, P_LIMIT, polish_record, record_scales,
    RecordScales)
from hydro_sdp.core.diagnosis.results import Candidate, Trial
from hydro_sdp.core.model.effects import LoadDependence
from hydro_sdp.core.model.exogenous_signals import record_key
from hydro_sdp.core.model.joint_model import JointModel
import numpy as np


class LoadDependenceDetector(EffectDetector):
    """The speed changes with the load: a factor of the measured load, or per record."""

    word = 'load_dependence'
    description = 'the speed changes with the load (payload, digging)'
    remedy = 'effect, a smooth factor of the measured load per direction'
    feature = 'command'
    state = 'load'

    def fit_effect(self, context: Context) -> Trial:
        """Fit on the measured load when every record has one, else per record."""
        if all(run.record.load is not None for run in context.runs):
            return self._fit_load(context)
        if len(context.runs) < 2:
            return Candidate(self.word, False, evidence='one record without a load signal: '
                             'nothing to compare its speed with'), None
        found = record_scales(context)
        if found.freedom == 0:
            return Candidate(self.word, True, evidence='no two records hold the same command '
                             'in the same direction'), None
        if found.p_value > P_LIMIT or found.spread < MIN_SPREAD:
            return Candidate(self.word, True, evidence=found.describe() + ': within noise'), None
        candidate, augmented = self._fit_records(context, found)
        if augmented is None:
            return candidate, augmented
        # Scales of the records themselves predict no other record, and without a load
        # signal the runs do not hold the cause: the finding is shown, the word refused.
        why = ('the records differ in speed beyond their noise, but they carry no load '
               'signal: a payload, the supply pressure or the oil temperature can do this; '
               'record the load (--load-topic: a cylinder pressure) to name it')
        return replace(candidate, refused=why, evidence=f'{why}; {candidate.evidence}'), augmented

    def _fit_load(self, context: Context) -> Trial:
        """Fit the smooth factor, the overrunning form and the power cap; keep the best sides."""
        samples = one_step_samples(context, END_SHARE)
        if not samples:
            return Candidate(self.word, True, evidence='no samples away from the ends of '
                             'the range'), None
        measured, predicted, load = (np.concatenate([part[i] for part in samples])
                                     for i in range(3))
        knots = load_knots(load[predicted != 0.0]) if np.any(predicted != 0.0) else \
            np.zeros(0)
        if knots.size < 2:
            return Candidate(self.word, True, evidence='the load does not change while the '
                             'joint moves'), None
        base = context.model.without_effect(self.word)
        share = context.naming.shares.get('load', 0.0)
        trials: list[Trial] = []
        tables = [('fitted to the increments', fitted_table(measured, predicted, load, knots))]
        read = sdp_table(context.naming, knots)
        if read is not None:
            tables.append(('as the SDP analysis draws it', read))
        for how, (up, down) in tables:
            effect = LoadDependence(knots=tuple(knots.tolist()),
                                    factors_positive=tuple(up.tolist()),
                                    factors_negative=tuple(down.tolist()))
            trials.append(context.score(
                self.word, base.with_effect(effect),
                {'knots': list(effect.knots), 'factors_positive': list(effect.factors_positive),
                 'factors_negative': list(effect.factors_negative)},
                f'the speed follows the load {how} (SDP share {100 * share:.3g} %): '
                f'{describe(knots, (up, down))}'))
        trials.append(self._fit_overrun(context, base, measured, predicted, load))
        trials.append(self._fit_cap(context, base, measured, predicted, load))
        return self._sides(context, base, trials)

    def _sides(self, context: Context, base: JointModel, trials: list[Trial]) -> Trial:
        """Give each direction the form that simulates the estimation runs best."""
        fitted = [(candidate, model.effect(self.word)) for candidate, model in trials
                  if model is not None]
        forms = [effect for _, effect in fitted if isinstance(effect, LoadDependence)]
        if not forms:
            return max(trials, key=lambda trial: trial[0].gain)
        effect, (up, down) = best_sides(base, forms, context.runs)
        if effect is None:
            return Candidate(self.word, True, evidence='no form of the load lowers the '
                             'simulation error of the estimation runs'), None
        parameters = {name: value for name, value in vars(effect).items()
                      if name not in ('records', 'record_positive', 'record_negative') and
                      value not in (0.0, ())}
        why = '; '.join(f'{name}: {fitted[index][0].evidence}' for name, index in
                        (('positive', up), ('negative', down)) if index >= 0)
        return context.score(self.word, base.with_effect(effect), parameters,
                             f'each direction in the form that simulates the estimation runs '
                             f'best ({why})')

    def _fit_overrun(self, context: Context, base: JointModel, measured: np.ndarray,
                     predicted: np.ndarray, load: np.ndarray) -> Trial:
        """Fit the overrunning load of a pressure-compensated valve per direction."""
        (up, up_onset), (down, down_onset) = [
            fit_overrun(measured[side], predicted[side], load[side])
            for side in (predicted > 0.0, predicted < 0.0)]
        if not (up or down):
            return Candidate(self.word, True, evidence='no load overruns the joint'), None
        effect = LoadDependence(overrun_positive=up, overrun_negative=down,
                                onset_positive=up_onset, onset_negative=down_onset)
        return context.score(
            self.word, base.with_effect(effect),
            {'overrun_positive': up, 'overrun_negative': down, 'onset_positive': up_onset,
             'onset_negative': down_onset},
            'an overrunning load speeds the joint up: the squared speed grows by '
            f'{up:+.3g} (positive) and {down:+.3g} (negative) per load unit beyond '
            f'{up_onset:.3g} and {down_onset:.3g}')

    def _fit_cap(self, context: Context, base: JointModel, measured: np.ndarray,
                 predicted: np.ndarray, load: np.ndarray) -> Trial:
        """Fit the pump's power cap per direction (:mod:`.power_cap`)."""
        (up, up_offset), (down, down_offset) = [
            fit_power_cap(measured[side], predicted[side], load[side])
            for side in (predicted > 0.0, predicted < 0.0)]
        if not (up or down):
            return Candidate(self.word, True, evidence='no power cap holds the joint back'), None
        dt = context.runs[0].dt
        effect = LoadDependence(limit_positive=up / dt, limit_negative=down / dt,
                                limit_offset_positive=up_offset,
                                limit_offset_negative=down_offset)
        caps = ', '.join(f'{limit / dt:.4g} / (L {offset:+.3g}) deg/s ({name})'
                         for limit, offset, name in ((up, up_offset, 'positive'),
                                                     (down, down_offset, 'negative')) if limit)
        return context.score(
            self.word, base.with_effect(effect),
            {'limit_positive': effect.limit_positive, 'limit_negative': effect.limit_negative,
             'limit_offset_positive': up_offset, 'limit_offset_negative': down_offset},
            f"the pump's power caps the speed as the load rises: at most {caps}")

    def _fit_records(self, context: Context, found: RecordScales) -> Trial:
        """Give each record its own scale per direction, polish, score."""
        keys = tuple(record_key(run.record) for run in context.runs)
        scales = found.scales
        travel = [(u if math.isfinite(u) else 1.0, d if math.isfinite(d) else 1.0)
                  for u, d in zip(scales['positive'], scales['negative'])]
        polished = [polish_record(context, run, key, up, down) for run, key, up, down in
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
        return first_significant(context, self.word, models, parameters, found.describe())

"""Detectors of timing: a wrong pure delay, a delay per direction (methods 8.2)."""

from __future__ import annotations

from dataclasses import replace

from hydro_sdp.core.diagnosis.context import Context
from hydro_sdp.core.diagnosis.detectors.base import Detector
from hydro_sdp.core.diagnosis.residuals import block_sums
from hydro_sdp.core.diagnosis.results import Candidate, Trial
from hydro_sdp.core.identification.delay import estimate_delay
from hydro_sdp.core.identification.experiment import thin
from hydro_sdp.core.identification.held_out import WindowErrors
from hydro_sdp.core.model.effects import DirectionDependentDelay
from hydro_sdp.core.model.sample_period import whole_samples_seconds
import numpy as np

#: How many of the delays the one-step residual ranks best the windowed error tells apart.
TOLD_APART = 5


class TimeDelayDetector(Detector):
    """The delay is wrong: re-estimate it by cross-correlation and by search on the records."""

    word = 'time_delay'
    description = 'the delay is wrong'
    remedy = 'the delay re-estimated'
    feature = 'events'
    state = 'since_change'

    def fit(self, context: Context) -> Trial:
        """Take the delay that predicts the records best; score the model with it."""
        current = context.model.delay_samples(context.dt)

        def cost(samples: int) -> float:
            return context.squared_residual(replace(context.model,
                                                    delay=samples * context.dt))
        # Every delay considered, and the cross-correlation estimate of the experiments
        # when there are any (it may lie beyond the search when the records are short).
        tried = list(range(0, context.max_delay + 1))
        estimated = None
        segmentation = context.segmentation
        if segmentation is not None and segmentation.experiments:
            experiments = thin(segmentation.experiments, 100_000)
            estimate = estimate_delay(experiments, context.dt, max_delay=context.max_delay,
                                      rest=segmentation.rest, noise=segmentation.noise_std)
            estimated = estimate.samples
            tried.append(estimated)
        # The one-step residual ranks the delays; the few best are told apart by the
        # simulation error over windows of the records, which a lag's transient does not
        # bias towards shorter delays (docs/methods.md section 8.2).
        ranked = sorted(dict.fromkeys(tried), key=cost)[:TOLD_APART]
        errors = WindowErrors(context.runs).compare(
            [replace(context.model, delay=samples * context.dt) for samples in ranked])
        best = ranked[int(np.argmin(errors))]
        how = 'as the experiments say' if best == estimated else 'the records say'

        if best == current:
            return Candidate(self.word, True, evidence=f'the data agree with the delay of '
                             f'{current} samples'), None
        delay = whole_samples_seconds(best, context.dt)
        candidate = replace(context.model, delay=delay)
        return context.score(self.word, candidate, {'delay': delay},
                             f'speed changes follow command changes after {best} samples, '
                             f'not {current} ({how})')


class DirectionDependentDelayDetector(Detector):
    """The two directions start after different delays: search each over the whole range."""

    word = 'direction_dependent_delay'
    description = 'the delay differs between directions'
    remedy = 'effect, delays by grid search'
    feature = 'events'
    state = 'since_change'

    def fit(self, context: Context) -> Trial:
        """Search each direction's delay in turn over every delay considered; score the pair."""
        current = context.model.delay_samples(context.dt)
        span = range(0, context.max_delay + 1)

        def cost(positive: int, negative: int) -> float:
            return context.squared_residual(context.model.with_effect(
                DirectionDependentDelay(positive * context.dt, negative * context.dt)))
        # Each direction's delay alone, from the model's; the one that helps more is kept
        # and the other searched again with it (the two interact where motion reverses).
        positive = min(span, key=lambda d: cost(d, current))
        negative = min(span, key=lambda d: cost(current, d))
        if cost(positive, current) <= cost(current, negative):
            negative = min(span, key=lambda d: cost(positive, d))
        else:
            positive = min(span, key=lambda d: cost(d, negative))
        base = float(block_sums(context.base, context.block).sum())
        if positive == negative or cost(positive, negative) >= base:
            return Candidate(self.word, True, evidence='both directions start after the same '
                             'delay'), None
        effect = DirectionDependentDelay(whole_samples_seconds(positive, context.dt),
                                         whole_samples_seconds(negative, context.dt))
        return context.score(self.word, context.model.with_effect(effect),
                             {'positive': effect.positive, 'negative': effect.negative},
                             f'motion in the positive direction starts {positive} samples '
                             f'after its command, in the negative direction {negative}')

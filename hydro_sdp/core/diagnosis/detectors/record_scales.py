"""Each record's speed scale per direction, and whether they differ (methods 8.2)."""

from __future__ import annotations

from dataclasses import dataclass
import math

from hydro_sdp.core.arrays import FloatArray
from hydro_sdp.core.diagnosis.context import Context
from hydro_sdp.core.diagnosis.detectors.overrun import inner_range
from hydro_sdp.core.diagnosis.residuals import mae, Run, run_increments
from hydro_sdp.core.diagnosis.results import Trial
from hydro_sdp.core.model.effects import LoadDependence
from hydro_sdp.core.model.joint_model import JointModel
from hydro_sdp.core.model.timing import delayed_at
import numpy as np
from scipy.optimize import minimize_scalar
# chi2's survival function without importing scipy.stats (0.7 s for one function).
from scipy.special import chdtrc

#: Heterogeneity of the per-record scales is named below this p-value.
P_LIMIT = 1e-3
#: ...and when the scales at one command differ by at least this share.
MIN_SPREAD = 0.03
#: Share of the angle range at either end left out of the per-record scales.
END_SHARE = 0.1


def block_scale(measured: FloatArray, predicted: FloatArray, block: int) -> tuple[float, float]:
    """
    Scale of the measured travel on the predicted travel, and its standard error.

    Returns: ``(scale, error)``; ``(nan, inf)`` when the predicted travel vanishes.
    """
    travel = float(np.sum(predicted))
    if not abs(travel) > 0.0 or predicted.size < 2 * block:
        return math.nan, math.inf
    scale = float(np.sum(measured)) / travel
    terms = measured - scale * predicted
    whole = terms.size // block * block
    sums = np.r_[terms[:whole].reshape(-1, block).sum(axis=1), terms[whole:].sum()]
    return scale, max(float(math.sqrt(np.sum(sums * sums))) / abs(travel), 1e-12)


def polish_record(context: Context, run: Run, key: str, up: float,
                  down: float) -> tuple[float, float]:
    """Return a record's speed factors per direction, fitted to its simulation error."""
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
        return float(chdtrc(self.freedom, self.statistic)) if self.freedom else 1.0

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
    predicted = [run_increments(context.model, run) for run in context.runs]
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


def first_significant(context: Context, word: str, models: list[JointModel],
                      parameters: list[dict[str, object]], evidence: str) -> Trial:
    """Score the models in turn; return the first significant one (else the last)."""
    trial: Trial | None = None
    for model, values in zip(models, parameters):
        trial = context.score(word, model, values, evidence)
        if trial[0].significant:
            break
    assert trial is not None
    return trial

"""Figures of the discrepancy workflow: residual signature, gap, gap ledger, record scales."""

from __future__ import annotations

from typing import Sequence

from hydro_sdp.core.arrays import FloatArray, IntArray
from hydro_sdp.core.diagnosis.results import Candidate, LedgerStep, Signature
from hydro_sdp.plots.figures import MEASURED, MODEL, new_figure
from matplotlib.axes import Axes
from matplotlib.figure import Figure
import numpy as np


def _binned(x: FloatArray, values: FloatArray, bins: int = 30,
            edges: FloatArray | None = None) -> tuple[FloatArray, FloatArray]:
    """Return bin centres of ``x`` and the mean of ``values`` in bins of more than 5."""
    if edges is None:
        edges = np.linspace(np.min(x), np.max(x), bins + 1)
    bins = edges.size - 1
    index = np.clip(np.digitize(x, edges) - 1, 0, bins - 1)
    counts = np.bincount(index, minlength=bins)
    sums = np.bincount(index, weights=values, minlength=bins)
    keep = counts > 5
    return 0.5 * (edges[1:] + edges[:-1])[keep], (sums / np.maximum(counts, 1))[keep]


def _event_average(signature: Signature, values: FloatArray,
                   span: int) -> tuple[IntArray, FloatArray]:
    """Return lags and the mean of ``values`` over the ``span`` samples after each trigger."""
    # Each event's residual is flipped by the sign of its change, so that rising and
    # falling changes add up instead of cancelling; a window never runs into the next run.
    rows = [sign * values[k:k + span]
            for k, sign in zip(signature.triggers.tolist(), signature.signs)
            if k + span <= signature.part_end(k)]
    if not rows:
        return np.arange(span), np.zeros(span)
    return np.arange(span), np.mean(rows, axis=0)


def plot_signature(signature: Signature, *, command_unit: str | None = None) -> Figure:
    """
    Draw the residual signature that named an effect, before and after adding it.

    ``signature``: residuals before and after, and what they are drawn against (from
    :attr:`hydro_sdp.core.diagnosis.Diagnosis.signature`).
    ``command_unit``: unit of the command, added to the label when the residual is drawn against it
    (default: none added).
    """
    figure, (ax,) = new_figure(1, height=3.8, width=8.0)
    dt = signature.dt
    curves = ((signature.before, MODEL, 'before'), (signature.after, MEASURED, 'after'))
    if signature.x is None:
        span = int(round(1.0 / dt))
        for values, colour, name in curves:
            lags, mean = _event_average(signature, values / dt, span)
            ax.plot(lags, mean, color=colour, linewidth=1.6, label=name)
    elif signature.signs.size == signature.x.size:
        _plot_by_direction(ax, signature)
    else:
        for values, colour, name in curves:
            centres, means = _binned(signature.x, values / dt)
            ax.plot(centres, means, 'o-', color=colour, markersize=3, linewidth=1.2, label=name)
    label = signature.label
    if signature.feature == 'command' and command_unit:
        label = f'{label} ({command_unit})'
    ax.set_xlabel(label)
    ax.axhline(0.0, color='black', linewidth=0.6)
    along = signature.x is not None and signature.signs.size == signature.x.size
    ax.set_ylabel('mean residual along the motion (deg/s)' if along else
                  'mean velocity residual (deg/s)')
    ax.legend(loc='best', fontsize=8, frameon=False)
    figure.suptitle(f'Residual signature of {signature.effect}', fontsize=11)
    return figure


def _plot_by_direction(ax: Axes, signature: Signature) -> None:
    """Draw the binned residual along the motion for each direction, before and after."""
    assert signature.x is not None
    moving = signature.signs != 0.0
    if not np.any(moving):
        return
    edges = np.linspace(np.min(signature.x[moving]), np.max(signature.x[moving]), 31)
    for values, colour, name in ((signature.before, MODEL, 'before'),
                                 (signature.after, MEASURED, 'after')):
        for sign, style, heading in ((1.0, '-', 'moving up'), (-1.0, '--', 'moving down')):
            mine = signature.signs == sign
            if np.count_nonzero(mine) > 5:
                centres, means = _binned(signature.x[mine], sign * values[mine] / signature.dt,
                                         edges=edges)
                ax.plot(centres, means, 'o' + style, color=colour, markersize=3,
                        linewidth=1.2, label=f'{name}, {heading}')


def plot_gap(t: FloatArray, measured: FloatArray, before: FloatArray, after: FloatArray, *,
             title: str = '') -> Figure:
    """Measured angle against the model before and after the named effects."""
    figure, (angle_ax, error_ax) = new_figure(2, height=2.8)
    time = t - t[0]
    angle_ax.plot(time, measured, color='black', linewidth=1.6, label='measured')
    angle_ax.plot(time, before, color=MODEL, linewidth=1.0, label='model before')
    angle_ax.plot(time, after, color=MEASURED, linewidth=1.0, linestyle='--',
                  label='model after')
    angle_ax.set_ylabel('angle (deg)')
    angle_ax.legend(loc='best', fontsize=8, frameon=False)
    error_ax.plot(time, measured - before, color=MODEL, linewidth=0.9, label='before')
    error_ax.plot(time, measured - after, color=MEASURED, linewidth=0.9, label='after')
    error_ax.axhline(0.0, color='black', linewidth=0.6)
    error_ax.set_ylabel('simulation error (deg)')
    error_ax.set_xlabel('time (s)')
    error_ax.legend(loc='best', fontsize=8, frameon=False)
    figure.suptitle(title or 'The gap between model and measurement', fontsize=11)
    return figure


def plot_ledger(mae_start: float, steps: Sequence[LedgerStep]) -> Figure:
    """
    Draw the validation MAE after each effect added (the gap ledger).

    ``mae_start``: MAE of the model given, degrees.
    """
    figure, (ax,) = new_figure(1, height=3.2, width=7.0)
    labels = ['model given'] + [f'+ {step.effect}' for step in steps]
    values = [mae_start] + [step.mae_after for step in steps]
    ax.bar(range(len(values)), values, color=[MODEL] + [MEASURED] * len(steps))
    for index, value in enumerate(values):
        ax.text(index, value, f'{value:.3g}', ha='center', va='bottom', fontsize=8)
    ax.set_xticks(range(len(values)), labels, fontsize=8)
    ax.set_yscale('log')
    ax.set_ylabel('validation MAE (deg, log scale)')
    figure.suptitle('Gap ledger', fontsize=11)
    return figure


def plot_record_scales(candidate: Candidate) -> Figure | None:
    """
    Draw each record's speed scale per direction with its error bars (``load_dependence``).

    ``candidate``: the ``load_dependence`` candidate; its parameters hold ``scales_positive``,
    ``errors_positive`` and the same for ``negative`` (None where a record does not move that way).
    Returns: the figure, or None when the candidate holds no scales.
    """
    if 'scales_positive' not in candidate.parameters:
        return None
    figure, (ax,) = new_figure(1, height=3.4, width=8.0)
    for offset, name, colour in ((-0.1, 'positive', MEASURED), (0.1, 'negative', MODEL)):
        scales = candidate.parameters[f'scales_{name}']
        errors = candidate.parameters[f'errors_{name}']
        if not isinstance(scales, list) or not isinstance(errors, list):
            continue
        shown = [(i, s, e) for i, (s, e) in enumerate(zip(scales, errors))
                 if s is not None and e is not None]
        if shown:
            index, value, error = (np.array(column, dtype=np.float64) for column in zip(*shown))
            ax.errorbar(index + offset, value, yerr=2.0 * error, fmt='o', color=colour,
                        markersize=4, capsize=2, label=f'{name} direction (+-2 s.e.)')
    ax.axhline(1.0, color='black', linewidth=0.6)
    ax.set_xlabel('record')
    ax.set_ylabel('measured / predicted travel')
    ax.legend(loc='best', fontsize=8, frameon=False)
    figure.suptitle('Speed scale of each record (load_dependence)', fontsize=11)
    return figure

"""Figures of what named an effect: the SDP estimate along its state, and every candidate."""

from __future__ import annotations

from typing import Sequence

from hydro_sdp.core.diagnosis.decision import MARGIN
from hydro_sdp.core.diagnosis.results import Candidate, StateEvidence
from hydro_sdp.plots.figures import LIMIT, MEASURED, MODEL, new_figure
from hydro_sdp.plots.sdp import draw_dependence, PARAMETERS, state_label
from matplotlib.figure import Figure
import numpy as np


def plot_state_evidence(evidence: StateEvidence, *, command_unit: str | None = None) -> Figure:
    """
    Draw what the model misses along the state that named the effect, before and after.

    ``evidence``: the SDP estimates of the model given and of the model with the effect.
    ``command_unit``: unit of the command, for the axis label.
    Returns: one panel for the ratio (each direction its colour), one for the residual; before
    solid with its band, after dashed with its band.
    """
    parameters = [p for p in ('ratio', 'residual')
                  if any(e.parameter == p for e in evidence.before + evidence.after)]
    figure, axes = new_figure(max(len(parameters), 1), height=3.2, width=7.5, sharex=True)
    for ax, parameter in zip(axes, parameters):
        for when, entries in (('before', evidence.before), ('after', evidence.after)):
            for entry in entries:
                if entry.parameter != parameter:
                    continue
                direction = '' if entry.direction == 'both' else f', {entry.direction}'
                draw_dependence(ax, entry, label=f'{when}{direction}', constant=False)
                if when == 'after':
                    ax.get_lines()[-1].set_linestyle('--')
        ax.axhline(1.0 if parameter == 'ratio' else 0.0, color=LIMIT, linewidth=0.8)
        ax.set_ylabel(PARAMETERS[parameter])
        ax.legend(loc='best', fontsize=8, frameon=False)
    axes[-1].set_xlabel(state_label(evidence.state, command_unit))
    figure.suptitle(f'What the model misses against {evidence.state}, which named '
                    f'{evidence.effect} (held-out share {100 * evidence.share:.3g} %); '
                    '+-2 standard errors', fontsize=10)
    return figure


def plot_candidates(candidates: Sequence[Candidate], named: str) -> Figure:
    """Draw what every word of the vocabulary explains on held-out data, and how sure that is."""
    shown = [c for c in candidates if c.applicable]
    figure, (size_ax, z_ax) = new_figure(2, height=2.6, width=8.0)
    place = np.arange(len(shown))
    colours = [MEASURED if c.accepted else LIMIT for c in shown]
    size_ax.bar(place, [100.0 * c.held_out for c in shown], color=colours)
    size_ax.axhline(100.0 * MARGIN, color=MODEL, linewidth=1.0, linestyle='--',
                    label=f'a name needs {100 * MARGIN:g} %')
    size_ax.set_ylabel('held-out error\nremoved (%)')
    size_ax.legend(loc='best', fontsize=8, frameon=False)
    # A stop's z runs to the hundreds: a log scale keeps the others readable.
    z_ax.bar(place, [max(min(c.t, 1e6), 0.1) for c in shown], color=colours)
    z_ax.set_yscale('log')
    z_ax.set_ylabel('bootstrap z')
    labels = [f'{c.effect}\n(named)' if c.effect == named else c.effect for c in shown]
    z_ax.set_xticks(place, labels, fontsize=7, rotation=30, ha='right')
    figure.suptitle('Candidates: what each word explains on held-out data', fontsize=11)
    return figure

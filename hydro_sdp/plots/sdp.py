"""Figures of the SDP analysis: each parameter against a state with +-2 standard-error bands."""

from __future__ import annotations

from typing import Sequence

from hydro_sdp.core.identification.state_dependence.dependence import SdpAnalysis, StateDependence
from hydro_sdp.core.identification.state_dependence.states import UNITS
from hydro_sdp.plots.figures import LIMIT, MEASURED, new_figure
from matplotlib.axes import Axes
from matplotlib.figure import Figure
import numpy as np

#: Colours of the directions of motion.
DIRECTION_COLOURS = {'positive': '#7570b3', 'negative': '#1b9e77', 'both': MEASURED}
#: Most points drawn per curve (the groups are thinned evenly beyond).
CURVE_POINTS = 1500
#: What each parameter is, for the axis labels.
PARAMETERS = {'b': 'gain b (deg per sample per unit)',
              'ratio': 'measured / model increment',
              'residual': 'increment residual (deg)',
              'a1': 'a1'}


def state_label(state: str, command_unit: str | None) -> str:
    """Return the axis label of a state, with its unit."""
    unit = command_unit if state == 'command' and command_unit else UNITS[state]
    names = {'command': 'delayed command', 'angle': 'angle y_{k-1}',
             'since_change': 'time since the command changed',
             'others_speed': "other joints' summed speed", 'load': 'measured load',
             'reversals': 'travel since the motion reversed'}
    return f'{names[state]} ({unit})'


def draw_dependence(ax: Axes, entry: StateDependence, *, label: str | None = None,
                    constant: bool = True) -> None:
    """
    Draw one parameter against its state: the estimate, its +-2 SE band, its constant.

    ``label``: legend label; default: its direction, share and significance.
    """
    colour = DIRECTION_COLOURS.get(entry.direction, MEASURED)
    values, estimate, se = entry.values, entry.estimate, entry.se
    if values.size > CURVE_POINTS:
        index = np.unique(np.round(np.linspace(0, values.size - 1, CURVE_POINTS)).astype(int))
        values, estimate, se = values[index], estimate[index], se[index]
    mark = 'significant' if entry.significant else 'not significant'
    text = label or (f'{entry.direction}: share {100 * entry.share:.1f} %, {mark}'
                     if entry.direction != 'both' else
                     f'share {100 * entry.share:.1f} %, {mark}')
    if values.size == 1 or values.size < 12:
        ax.errorbar(values, estimate, yerr=2.0 * se, fmt='o-', color=colour, markersize=4,
                    capsize=3, linewidth=1.4, label=text)
    else:
        ax.fill_between(values, estimate - 2.0 * se, estimate + 2.0 * se, color=colour,
                        alpha=0.2, linewidth=0)
        ax.plot(values, estimate, color=colour, linewidth=1.6, label=text)
    if constant:
        lo, hi = float(np.min(values)), float(np.max(values))
        ax.plot([lo, hi], [entry.constant, entry.constant], color=colour, linestyle='--',
                linewidth=0.9)


def plot_state(analysis: SdpAnalysis, state: str, *, command_unit: str | None = None,
               title: str = '') -> Figure:
    """
    Draw every parameter of the analysis against one state.

    ``command_unit``: unit of the command, for the axis label.
    """
    gains = [e for e in analysis.states if e.state == state]
    residual = [e for e in analysis.residual if e.state == state]
    rows = 1 + bool(residual)
    figure, axes = new_figure(rows, height=3.4, width=7.5, sharex=True)
    for entry in gains:
        draw_dependence(axes[0], entry)
    parameter = gains[0].parameter if gains else 'b'
    axes[0].set_ylabel(PARAMETERS[parameter])
    if parameter == 'ratio':
        axes[0].axhline(1.0, color=LIMIT, linewidth=0.8)
    for entry in residual:
        draw_dependence(axes[1], entry)
        axes[1].axhline(0.0, color=LIMIT, linewidth=0.8)
        axes[1].set_ylabel(PARAMETERS['residual'])
    for ax in axes:
        ax.legend(loc='best', fontsize=8, frameon=False)
    axes[-1].set_xlabel(state_label(state, command_unit))
    first = analysis.states[0].state if analysis.states else ''
    what = 'alone' if state == first else f'added to {first}'
    figure.suptitle(title or f'{parameter} against {state} ({what}), +-2 standard errors',
                    fontsize=11)
    return figure


def plot_shares(analysis: SdpAnalysis, *, title: str = '') -> Figure:
    """
    Draw the share of the squared residual each state explains, per direction.

    Returns: the figure: one bar per state and direction, hatched when not significant.
    """
    entries: Sequence[StateDependence] = analysis.states
    figure, (ax,) = new_figure(1, height=0.35 * max(len(entries), 3) + 1.0, width=7.0)
    names = [f'{e.state} ({e.direction})' for e in entries]
    position = np.arange(len(entries))[::-1]
    for y, entry in zip(position, entries):
        ax.barh(y, 100.0 * entry.share, color=DIRECTION_COLOURS.get(entry.direction, MEASURED),
                hatch='' if entry.significant else '//', edgecolor='white',
                alpha=1.0 if entry.significant else 0.45)
    ax.set_yticks(position, names, fontsize=8)
    ax.set_xlabel('held-out share of the squared residual (%); hatched: not significant')
    parameter = entries[0].parameter if entries else 'b'
    figure.suptitle(title or f'What each state explains of {parameter} '
                    f'({analysis.samples} samples; first alone, the others added to it)',
                    fontsize=10)
    return figure

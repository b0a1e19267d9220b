"""Figure basics: the colours, a new figure with stacked axes, saving it whole."""

from __future__ import annotations

import io
import math
import os
from pathlib import Path
from typing import Literal

from hydro_sdp.core.model.joint_model import JointModel
from hydro_sdp.io.atomic import atomic_write_bytes
from hydro_sdp.plots.units import command_unit_of
from matplotlib.axes import Axes
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.colors import Colormap
from matplotlib.figure import Figure

#: Colours used throughout: measured data, model, limits.
MEASURED = '#1f4e79'
MODEL = '#d95f02'
LIMIT = '#7f7f7f'

#: Where a legend may go (matplotlib's names).
LegendPlace = Literal['best', 'upper left', 'upper right', 'lower left', 'lower right',
                      'center left', 'center right']


def new_figure(rows: int = 1, *, height: float = 2.6, width: float = 9.0,
               sharex: bool = True) -> tuple[Figure, list[Axes]]:
    """
    Create a figure with ``rows`` stacked axes sharing the time axis.

    ``sharex``: whether the subplots share their x axis.
    Returns: the figure and a list of its axes.
    """
    figure = Figure(figsize=(width, height * rows + 0.6), layout='constrained')
    FigureCanvasAgg(figure)
    axes = figure.subplots(rows, 1, sharex=sharex, squeeze=False)[:, 0]
    for ax in axes:
        ax.grid(True, color='#dddddd', linewidth=0.6)
        ax.set_axisbelow(True)
    return figure, list(axes)


def save_figure(figure: Figure, path: str | os.PathLike[str], *, dpi: int = 130) -> Path:
    """Save a figure as PNG, whole or not at all."""
    buffer = io.BytesIO()
    # zlib's fastest level: files a tenth larger; the default level's compression took
    # about a seventh of a figure's time.
    figure.savefig(buffer, format='png', dpi=dpi, pil_kwargs={'compress_level': 1})
    return atomic_write_bytes(path, buffer.getvalue())


def mark_limits(ax: Axes, limits: tuple[float, float] | None, label: str) -> None:
    """Draw a pair of horizontal limits, dashed, labelled at the right edge."""
    if limits is None:
        return
    shown = [value for value in limits if math.isfinite(value)]
    for value in shown:
        ax.axhline(value, color=LIMIT, linestyle='--', linewidth=0.9)
    if shown:
        ax.text(1.0, shown[-1], f' {label}', transform=ax.get_yaxis_transform(),
                color=LIMIT, fontsize=8, va='center', ha='left', clip_on=False)


def mark_dead_zone(ax: Axes, dead_zone: tuple[float, float]) -> None:
    """Draw a dead-zone against the command: its edges dashed, the band between them shaded."""
    for edge in dead_zone:
        ax.axvline(edge, color=LIMIT, linestyle='--', linewidth=0.9)
    ax.axvspan(*dead_zone, color=LIMIT, alpha=0.12, linewidth=0, label='dead-zone')


def label_command_axes(ax: Axes, model: JointModel, command_unit: str | None, ylabel: str,
                       legend: LegendPlace) -> None:
    """Label axes whose x is the steady command, in its unit; put the legend at ``legend``."""
    ax.set_xlabel(f'steady command v ({command_unit_of(model, command_unit)})')
    ax.set_ylabel(ylabel)
    ax.legend(loc=legend, fontsize=8, frameon=False)


def matplotlib_colormap() -> Colormap:
    """Return the diverging colour map used for command levels."""
    from matplotlib import colormaps
    return colormaps['coolwarm']

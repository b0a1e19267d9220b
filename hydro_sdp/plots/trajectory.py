"""Figures of trajectory following: the bucket tip on a straight line (Fig. 7 style)."""

from __future__ import annotations

from hydro_sdp.core.arrays import FloatArray
from hydro_sdp.plots.figures import LIMIT, MEASURED, MODEL
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
import numpy as np


def plot_tip_path(t: FloatArray, x: FloatArray, z: FloatArray,
                  line: tuple[tuple[float, float], tuple[float, float]],
                  path_error_mm: FloatArray, *, motion: tuple[float, float] | None = None,
                  title: str = '') -> Figure:
    """
    Draw the simulated tip against the straight line, and its distance from it.

    Parameters
    ----------
    t : FloatArray
        Time, s.
    x, z : FloatArray
        Simulated tip, m.
    line : tuple of two (x, z) points
        Ends of the line, m.
    path_error_mm : FloatArray
        Distance of the tip from the line at each time, mm.
    motion : tuple[float, float] or None
        Start and end of the motion, s (shaded in the error panel).
    title : str
        Figure title.

    Returns
    -------
    Figure
        The figure: left, ``z`` against ``x`` (equal scales); right, the path
        error in mm against time.

    """
    figure = Figure(figsize=(11.0, 4.4), layout='constrained')
    FigureCanvasAgg(figure)
    path_ax, error_ax = figure.subplots(1, 2, width_ratios=[1.0, 1.3])
    for ax in (path_ax, error_ax):
        ax.grid(True, color='#dddddd', linewidth=0.6)
        ax.set_axisbelow(True)
    (x0, z0), (x1, z1) = line
    path_ax.plot([x0, x1], [z0, z1], color=MODEL, linestyle='--', linewidth=1.4,
                 label='demanded line')
    path_ax.plot(x, z, color=MEASURED, linewidth=1.2, label='bucket tip')
    path_ax.plot([x0], [z0], marker='o', color=MODEL, markersize=4)
    path_ax.set_aspect('equal', adjustable='datalim')
    path_ax.set_xlabel('x (m, forward)')
    path_ax.set_ylabel('z (m, up)')
    path_ax.legend(loc='upper right', fontsize=8, frameon=False)
    if motion is not None:
        error_ax.axvspan(motion[0], motion[1], color=LIMIT, alpha=0.12, linewidth=0,
                         label='motion')
    error_ax.plot(t, path_error_mm, color=MEASURED, linewidth=1.2, label='distance from line')
    error_ax.set_xlabel('time (s)')
    error_ax.set_ylabel('path error (mm)')
    error_ax.set_ylim(bottom=0.0, top=max(1.0, 1.1 * float(np.max(path_error_mm, initial=0.0))))
    error_ax.legend(loc='upper left', fontsize=8, frameon=False)
    figure.suptitle(title or 'Straight-line bucket path', fontsize=11)
    return figure

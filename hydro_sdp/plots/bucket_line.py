"""The bucket tip on a straight line with the two joints' tracking (the LUCIE paper's Fig. 7)."""

from __future__ import annotations

from typing import Sequence

from hydro_sdp.core.arrays import FloatArray
from hydro_sdp.core.control.loop_simulation import LoopTrace
from hydro_sdp.plots.figures import LIMIT, MEASURED, MODEL
from matplotlib.axes import Axes
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
import numpy as np


def _grid(ax: Axes) -> None:
    ax.grid(True, color='#dddddd', linewidth=0.6)
    ax.set_axisbelow(True)


def _shade(ax: Axes, motion: tuple[float, float]) -> None:
    ax.axvspan(motion[0], motion[1], color=LIMIT, alpha=0.10, linewidth=0, label='motion')


def _mark_after_motion(ax: Axes, t: FloatArray, path_error_mm: FloatArray,
                       motion: tuple[float, float]) -> None:
    """Point at the largest distance after the motion ended, saying the motion had ended."""
    after = np.flatnonzero(t > motion[1])
    if after.size == 0:
        return
    peak = int(after[np.argmax(path_error_mm[after])])
    ax.annotate(f'{path_error_mm[peak]:.1f} mm after the motion ended\n(the joints settle at '
                'the end point)', xy=(float(t[peak]), float(path_error_mm[peak])),
                xytext=(0.97, 0.93), textcoords='axes fraction', ha='right', va='top',
                fontsize=8, arrowprops={'arrowstyle': '->', 'color': LIMIT, 'linewidth': 0.8})


def plot_bucket_line(x: FloatArray, z: FloatArray,
                     line: tuple[tuple[float, float], tuple[float, float]],
                     path_error_mm: FloatArray, traces: Sequence[LoopTrace],
                     motion: tuple[float, float], *, magnify: float = 100.0,
                     title: str = '') -> Figure:
    """
    Draw the bucket tip against its straight line, the path error and each joint's tracking.

    ``x``, ``z``: tip at every plant sample, m (``traces[0].t`` is the time).
    ``line``: start and end of the demanded line, m.
    ``path_error_mm``: distance of the tip from the line at every sample, mm.
    ``traces``: the joints' traces (boom, dipper), angles in degrees.
    ``motion``: start and end of the motion along the line, s (shaded).
    ``magnify``: factor the tip's sideways deviation from the line is drawn at in the path panel (a
    millimetre error is invisible on a metre line).
    Returns: top: the tip path in the arm's plane (equal scales) and the path error in mm against
    time; below, the demanded and actual angle of each joint (as the paper's Fig. 7 (a) and (b)).
    """
    rows = 1 + (len(traces) + 1) // 2
    figure = Figure(figsize=(11.0, 0.6 + 3.4 * rows), layout='constrained')
    FigureCanvasAgg(figure)
    axes = figure.subplots(rows, 2, squeeze=False)
    path_ax, error_ax = axes[0]
    joint_axes = list(axes[1:].ravel())
    for ax in axes.ravel():
        _grid(ax)
    t = traces[0].t
    moving = (t >= motion[0]) & (t <= motion[1])
    (x0, z0), (x1, z1) = line
    length = float(np.hypot(x1 - x0, z1 - z0))
    # Unit normal of the line: the tip is drawn with its signed offset along it magnified.
    nx, nz = -(z1 - z0) / length, (x1 - x0) / length
    offset = (x - x0) * nx + (z - z0) * nz
    # Only the motion: after it the joints settle and the magnified offset says nothing new.
    shown = (magnify - 1.0) * offset[moving]
    path_ax.plot(x[moving] + shown * nx, z[moving] + shown * nz, color=MEASURED, linewidth=1.4,
                 label=f'bucket tip in motion (deviation x{magnify:g})', zorder=2)
    # The demanded line on top, dashed, so that the tip shows through where they meet.
    path_ax.plot([x0, x1], [z0, z1], color=MODEL, linestyle=(0, (5, 4)), linewidth=2.0,
                 label='demanded line', zorder=3)
    path_ax.plot([x0], [z0], marker='o', color=MODEL, markersize=6, linestyle='none',
                 label='start')
    path_ax.plot([x1], [z1], marker='s', color=MODEL, markersize=6, linestyle='none',
                 label='end')
    path_ax.set_aspect('equal', adjustable='datalim')
    path_ax.set_xlabel('x (m, forward of the boom pivot)')
    path_ax.set_ylabel('z (m, up)')
    path_ax.legend(loc='upper right', fontsize=8, frameon=False)
    _shade(error_ax, motion)
    error_ax.plot(t, path_error_mm, color=MEASURED, linewidth=1.2, label='distance from line')
    if moving.any():
        worst = float(np.max(path_error_mm[moving]))
        rms = float(np.sqrt(np.mean(path_error_mm[moving] ** 2)))
        error_ax.text(0.02, 0.72, f'in motion: max {worst:.2f} mm, RMS {rms:.2f} mm',
                      transform=error_ax.transAxes, ha='left', va='top', fontsize=8)
    _mark_after_motion(error_ax, t, path_error_mm, motion)
    error_ax.set_xlabel('time (s)')
    error_ax.set_ylabel('path error (mm)')
    error_ax.set_ylim(bottom=0.0, top=max(1.0, 1.4 * float(np.max(path_error_mm, initial=0.0))))
    error_ax.legend(loc='upper left', fontsize=8, frameon=False)
    for ax, trace in zip(joint_axes, traces):
        _shade(ax, motion)
        ax.plot(trace.t, trace.setpoint, color=MODEL, linestyle='--', linewidth=1.6,
                label='demanded')
        ax.plot(trace.t, trace.y, color=MEASURED, linewidth=1.1, label='actual')
        error = (trace.y - trace.setpoint)[moving]
        rising = trace.setpoint[-1] > trace.setpoint[0]
        joint_rms, joint_max = np.sqrt(np.mean(error ** 2)), np.max(np.abs(error))
        ax.text(0.98 if rising else 0.02, 0.04,
                f'in motion: RMS error {joint_rms:.2f} deg, max {joint_max:.2f} deg',
                transform=ax.transAxes, ha='right' if rising else 'left', va='bottom', fontsize=8)
        ax.set_title(f'{trace.joint} angle tracking', fontsize=9)
        ax.set_xlabel('time (s)')
        ax.set_ylabel(f'{trace.joint} angle (deg)')
        ax.legend(loc='upper left' if rising else 'upper right', fontsize=8, frameon=False)
    for ax in joint_axes[len(traces):]:
        ax.set_visible(False)
    figure.suptitle(title or 'Straight-line bucket path', fontsize=11)
    return figure

"""Figures of experiments and identification, after West et al. (2018), Figs. 1-4."""

from __future__ import annotations

from typing import Sequence

from hydro_sdp.core.identification.delay import LevelSpeed
from hydro_sdp.core.identification.experiment import Experiment
from hydro_sdp.core.identification.state_dependence.dependence import StateDependence
from hydro_sdp.core.model.joint_model import JointModel
from hydro_sdp.core.model.records import Record
from hydro_sdp.plots.figures import (
    label_command_axes, LIMIT, mark_dead_zone, mark_limits, matplotlib_colormap, MEASURED, MODEL,
    new_figure)
from hydro_sdp.plots.sdp import draw_dependence
from hydro_sdp.plots.units import command_unit_of
from matplotlib.figure import Figure
import numpy as np
from numpy.typing import ArrayLike


def plot_record(record: Record, model: JointModel | None = None, *,
                simulated: np.ndarray | None = None, title: str = '',
                command_unit: str | None = None) -> Figure:
    """
    Angle (upper) and command (lower) against time, as the paper's Fig. 4.

    ``model``: marks end stops and the dead-zone when given.
    ``simulated``: model response to overlay on the angle, degrees.
    ``command_unit``: unit of the command, for the axis label; default: from the model's input
    range (:func:`~hydro_sdp.plots.units.command_unit_of`).
    """
    figure, (angle_ax, command_ax) = new_figure(2)
    time = record.t - record.t[0]
    angle_ax.plot(time, record.y, color=MEASURED, linewidth=1.6 if simulated is not None else 1.0,
                  label='measured')
    if simulated is not None:
        angle_ax.plot(time, simulated, color=MODEL, linewidth=0.9, label='model')
        angle_ax.legend(loc='upper right', fontsize=8, frameon=False)
    angle_ax.set_ylabel('joint angle y (deg)')
    command_ax.step(time, record.v, where='post', color=MEASURED, linewidth=0.9)
    command_ax.set_ylabel(f'command v ({command_unit_of(model, command_unit)})')
    command_ax.set_xlabel('time (s)')
    if model is not None:
        mark_limits(angle_ax, model.angle_limits, 'end stops')
        if model.dead_zone is not None:
            command_ax.axhspan(*model.dead_zone, color=LIMIT, alpha=0.15, linewidth=0)
            command_ax.text(1.0, model.dead_zone[1], ' dead-zone',
                            transform=command_ax.get_yaxis_transform(), color=LIMIT,
                            fontsize=8, va='bottom', ha='left', clip_on=False)
    figure.suptitle(title or f'joint {record.joint}', fontsize=11)
    return figure


def plot_velocity_map(model: JointModel, *, v_range: tuple[float, float] | None = None,
                      title: str = '', command_unit: str | None = None,
                      points: tuple[ArrayLike, ArrayLike] | None = None,
                      points_label: str = 'experiments') -> Figure:
    """
    Angular velocity against steady command, as the paper's Fig. 3.

    ``model``: the joint; its map is drawn, with dead-zone and saturation marked.
    ``v_range``: command range; default: the input limits, or +-5 units.
    ``command_unit``: unit of the command; default: from the model's input range.
    ``points``: per-experiment ``(v, velocity)`` estimates to show as circles.
    """
    figure, (ax,) = new_figure(1, height=4.0, width=7.0)
    low, high = v_range or model.input_limits or (-5.0, 5.0)
    v = np.linspace(low, high, 801)
    ax.plot(v, model.rate(v), color=MODEL, linewidth=1.8, label=f'{model.kind} map')
    if points is not None:
        ax.plot(points[0], points[1], 'o', color=MEASURED, markersize=4,
                markerfacecolor='none', label=points_label)
    if model.dead_zone is not None:
        mark_dead_zone(ax, model.dead_zone)
    saturation = getattr(model.static_map, 'saturation_velocity', None)
    if saturation is not None:
        for speed in saturation:
            ax.axhline(speed, color=LIMIT, linestyle=':', linewidth=0.9)
    label_command_axes(ax, model, command_unit, 'angular velocity (deg/s)', 'center left')
    figure.suptitle(title or f'velocity map of joint {model.joint}', fontsize=11)
    return figure


def plot_step_responses(experiments: Sequence[Experiment], delay: int, dt: float, *,
                        title: str = '') -> Figure:
    """
    Step responses and differenced angles against sample, as the paper's Fig. 1.

    ``experiments``: experiments; only steps are drawn, each normalised to start at 0.
    ``delay``: estimated delay, samples, drawn dashed.
    ``dt``: sample period, s.
    """
    figure, (angle_ax, step_ax) = new_figure(2, height=2.8)
    steps = [e for e in experiments if e.kind == 'step']
    levels = np.array([e.level for e in steps]) if steps else np.zeros(1)
    scale = max(np.max(np.abs(levels)), 1e-12)
    colormap = matplotlib_colormap()
    for experiment in steps:
        k = np.arange(experiment.y.size - experiment.start)
        angle = experiment.y[experiment.start:] - experiment.y[experiment.start]
        colour = colormap(0.5 + 0.5 * experiment.level / scale)
        angle_ax.plot(k, angle, color=colour, linewidth=0.8)
        step_ax.plot(k[1:], np.diff(angle), color=colour, linewidth=0.6)
    for ax in (angle_ax, step_ax):
        ax.axvline(delay, color=LIMIT, linestyle='--', linewidth=1.0)
    angle_ax.text(delay, 1.0, f' tau = {delay} samples ({delay * dt:g} s)', color=LIMIT,
                  fontsize=8, transform=angle_ax.get_xaxis_transform(), va='top')
    angle_ax.set_ylabel('angle y_k - y_0 (deg)')
    step_ax.set_ylabel('y_k - y_{k-1} (deg)')
    step_ax.set_xlabel(f'sample k after the step (dt = {dt:g} s)')
    figure.suptitle(title or f'{len(steps)} step experiments (colour: command, blue < 0 < red)',
                    fontsize=11)
    return figure


def plot_gains(points: Sequence[LevelSpeed], model: JointModel, dt: float, *, rest: float = 0.0,
               command_unit: str | None = None,
               measured: Sequence[StateDependence] = (),
               points_label: str = 'per experiment (RIV)') -> Figure:
    """
    State-dependent gain against command, as the paper's Fig. 2.

    ``model``: the identified model; its ``b_tau(v) = dt rate(v) / (v - rest)`` is drawn.
    ``dt``: sample period, s.
    ``command_unit``: unit of the command; default: from the model's input range.
    ``measured``: the gain estimated along the delayed command without a map family (the SDP
    analysis, one entry per direction), drawn with its +-2 standard-error band.
    """
    figure, (ax,) = new_figure(1, height=4.0, width=7.0)
    for entry in measured:
        draw_dependence(ax, entry, label=f'measured, {entry.direction} (SDP, +-2 SE)',
                        constant=False)
    levels = np.array([p.level for p in points if p.level != rest])
    gains = np.array([p.gain * 1.0 for p in points if p.level != rest])
    ax.plot(levels, gains, 'o', color=MEASURED, markerfacecolor='none', markersize=5,
            label=points_label)
    span = max(np.max(np.abs(levels - rest)), 1e-9) if levels.size else 1.0
    v = np.linspace(rest - 1.05 * span, rest + 1.05 * span, 801)
    v = v[np.abs(v - rest) > 1e-9 * span]
    ax.plot(v, dt * model.rate(v) / (v - rest), color=MODEL, linewidth=1.8,
            label=f'{model.kind} model')
    label_command_axes(ax, model, command_unit, 'b_tau (deg per sample per unit)', 'upper left')
    figure.suptitle(f'State-dependent gain of joint {model.joint} (West et al. 2018, Fig. 2)',
                    fontsize=11)
    return figure

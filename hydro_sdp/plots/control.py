"""Figures of control: the IDZ, closed-loop responses, recalibration (Figs. 6-7)."""

from __future__ import annotations

from typing import Sequence

from hydro_sdp.core.control.idz import InverseDeadZone
from hydro_sdp.core.control.idz_table import TableInverseDeadZone
from hydro_sdp.core.control.loop_chatter import hold_pulses
from hydro_sdp.core.control.loop_simulation import LoopTrace
from hydro_sdp.core.model.joint_model import JointModel
from hydro_sdp.plots.figures import (
    label_command_axes, LIMIT, mark_dead_zone, MEASURED, MODEL, new_figure)
from hydro_sdp.plots.units import UNKNOWN_UNIT
from matplotlib.figure import Figure
import numpy as np

#: Colour of the valve's pulses at hold.
PULSE = '#c00000'
#: The controller on the worst of the plausible models (dash-dot, beside the nominal).
WORST = '#e6ab02'


def plot_idz(model: JointModel, idz: InverseDeadZone, control_period: float, *,
             u_limits: tuple[float, float] | None = None,
             v_range: tuple[float, float] | None = None,
             command_unit: str | None = None) -> Figure:
    """
    IDZ approximation, as the paper's Fig. 6.

    ``control_period``: control period, s.
    ``u_limits``: limits of the controller's ``u``, drawn as dotted lines.
    ``v_range``: command range to draw; default: to where the model saturates (99 %).
    ``command_unit``: unit of the command; default: from the model's input range.
    """
    figure, (ax,) = new_figure(1, height=4.2, width=7.5)
    low, high = idz.dead_zone
    if v_range is None:
        curvature = getattr(model.static_map, 'curvature', None)
        if curvature is not None:
            v_range = (low - np.log(100.0) / curvature[0], high + np.log(100.0) / curvature[1])
        else:
            width = max(high - low, 0.1 * max(abs(low), abs(high), 1.0))
            v_range = (low - 2.0 * width, high + 2.0 * width)
        if model.input_limits is not None:
            v_range = (max(v_range[0], model.input_limits[0]),
                       min(v_range[1], model.input_limits[1]))
    v = np.linspace(v_range[0], v_range[1], 801)
    ax.plot(v, model.rate(v) * control_period, color=MODEL, linewidth=1.2,
            label=f'{model.kind} model')
    chord = np.array([idz.increment(x) for x in v])
    ax.plot(v, chord, color=MEASURED, linewidth=2.2, label='linearised (the IDZ inverts this)')
    mark_dead_zone(ax, (low, high))
    if u_limits is not None:
        for value in u_limits:
            ax.axhline(value, color=LIMIT, linestyle=':', linewidth=1.0)
        ax.text(1.0, u_limits[1], ' u limit', transform=ax.get_yaxis_transform(),
                color=LIMIT, fontsize=8, va='center', ha='left', clip_on=False)
    ax.axhline(0.0, color='black', linewidth=0.6)
    label_command_axes(ax, model, command_unit,
                       f'increment q (deg per {control_period:g} s sample)', 'upper left')
    figure.suptitle(f'IDZ approximation of joint {model.joint} '
                    f'(slopes {idz.slopes[0]:.4g}, {idz.slopes[1]:.4g}; beta {idz.beta:g})',
                    fontsize=11)
    return figure


def plot_idz_table(model: JointModel, table: TableInverseDeadZone, chord: InverseDeadZone,
                   control_period: float, *, command_unit: str | None = None) -> Figure:
    """
    Draw the map's table IDZ next to the paper's chord IDZ, and the loop gain each leaves.

    ``control_period``: control period, s.
    ``command_unit``: unit of the command; default: from the model's input range.
    """
    figure, (ax, gain_ax) = new_figure(2, height=3.4, width=7.5, sharex=False)
    v = np.linspace(table.v[0], table.v[-1], 1201)
    ax.plot(v, model.rate(v) * control_period, color=MODEL, linewidth=3.0,
            label=f'{model.kind} model')
    ax.plot(table.v, table.u, color=MEASURED, linewidth=1.0, marker='o', markersize=2.5,
            label=f'table: {len(table.u)} points (the IDZ inverts this)')
    ax.plot(v, [chord.increment(x) for x in v], color=LIMIT, linestyle='--', linewidth=1.2,
            label="chords (the paper's IDZ)")
    mark_dead_zone(ax, table.dead_zone)
    ax.axhline(0.0, color='black', linewidth=0.6)
    ax.set_ylim(1.15 * table.u[0], 1.15 * table.u[-1])
    label_command_axes(ax, model, command_unit,
                       f'increment q (deg per {control_period:g} s sample)', 'upper left')
    u = np.linspace(table.u[0], table.u[-1], 1200)
    u = u[np.abs(u) > max(table.beta, 1e-9)]        # the band sends u to rest
    for idz, colour, style, name in ((table, MEASURED, '-', 'table'),
                                     (chord, LIMIT, '--', 'chords')):
        gain = [control_period * float(model.rate(idz.command(float(x))[0])) / x for x in u]
        gain_ax.plot(u, gain, color=colour, linestyle=style, linewidth=1.4, label=name)
    gain_ax.axhline(1.0, color='black', linewidth=0.6)
    gain_ax.set_xlabel(f'PIP output u (deg per {control_period:g} s sample)')
    gain_ax.set_ylabel('loop gain q(IDZ(u)) / u')
    gain_ax.legend(loc='upper right', fontsize=8, frameon=False)
    figure.suptitle(f"IDZ of joint {model.joint}: the map's own inverse and its chords "
                    f'(beta {table.beta:.3g})', fontsize=11)
    return figure


def plot_closed_loop(traces: Sequence[LoopTrace], *, title: str = '',
                     command_unit: str | None = None,
                     valve: tuple[tuple[float, float], float] | None = None,
                     worst: tuple[LoopTrace, str] | None = None) -> Figure:
    """
    Closed-loop response, as the paper's Fig. 7: angle, u and v against time.

    ``command_unit``: unit of the valve command (default: ``input units``; see
    :func:`~hydro_sdp.plots.units.command_unit_of` for a model's).
    ``valve``: ``(edges, rest)`` of the valve's dead-zone: its edges are drawn and the valve's
    pulses across it at hold marked (methods.md section 5.7).
    ``worst``: ``(trace, name)``: the same controller on the worst of the models the data do not
    rule out (methods.md section 5.8), drawn beside the first trace.
    """
    # Joints at different angles hide each other's errors: give them a panel of their own.
    several = len(traces) > 1
    figure, axes = new_figure(4 if several else 3, height=2.2)
    angle_ax, u_ax, v_ax = axes[0], axes[-2], axes[-1]
    colours = [MEASURED, MODEL, '#1b9e77', '#7570b3']
    for index, trace in enumerate(traces):
        colour = colours[index % len(colours)]
        label = trace.joint
        angle_ax.plot(trace.t, trace.setpoint, color=colour, linestyle='--', linewidth=1.0)
        angle_ax.plot(trace.t, trace.y, color=colour, linewidth=1.4, label=label)
        if several:
            axes[1].plot(trace.t, trace.y - trace.setpoint, color=colour, linewidth=1.0)
        u_ax.plot(trace.t, trace.u, color=colour, linewidth=1.0, drawstyle='steps-pre')
        v_ax.plot(trace.t, trace.v, color=colour, linewidth=1.0, drawstyle='steps-pre')
        if valve is not None:
            pulses = hold_pulses(trace, valve[0], valve[1])
            v_ax.plot(trace.t[pulses], trace.v[pulses], linestyle='none', marker='v',
                      markersize=5, color=PULSE,
                      label=f'{pulses.size} pulse{"" if pulses.size == 1 else "s"} at hold')
    if worst is not None:
        trace, name = worst
        angle_ax.plot(trace.t, trace.y, color=WORST, linewidth=1.0, linestyle='-.',
                      label=f'worst plausible model: {name}')
        v_ax.plot(trace.t, trace.v, color=WORST, linewidth=0.8, drawstyle='steps-pre',
                  label='its valve')
    if valve is not None or worst is not None:
        v_ax.legend(loc='upper right', fontsize=8, frameon=False,
                    title='dotted: dead-zone edges' if valve is not None else None,
                    title_fontsize=8)
    if valve is not None:
        for edge in valve[0]:
            v_ax.axhline(edge, color=LIMIT, linestyle=':', linewidth=0.8)
    if several:
        axes[1].axhline(0.0, color='black', linewidth=0.6)
        axes[1].set_ylabel('error y - d (deg)')
    angle_ax.set_ylabel('angle y (deg)')
    angle_ax.legend(loc='lower right', fontsize=8, frameon=False,
                    title='dashed: set-point', title_fontsize=8)
    u_ax.set_ylabel('PIP input u\n(deg/sample)')
    v_ax.set_ylabel(f'valve v ({command_unit or UNKNOWN_UNIT})')
    v_ax.set_xlabel('time (s)')
    figure.suptitle(title or 'PIP-IDZ closed loop', fontsize=11)
    return figure


def plot_recalibration(t: np.ndarray, angle: np.ndarray, setpoint: np.ndarray,
                       command: np.ndarray, edges: np.ndarray, drift: float, *,
                       command_unit: str = 'V') -> Figure:
    """
    Draw a loop whose dead-zone drifts and whose IDZ the identifier recalibrates.

    ``angle``, ``setpoint``: joint angle and set-point, degrees.
    ``command``: valve command, input units.
    ``edges``: ``(samples, 2)`` IDZ edges the controller used, input units.
    ``drift``: time the plant's dead-zone moved, s.
    ``command_unit``: unit of the command (the recalibration scenario runs the J2 joint, in V).
    """
    figure, (angle_ax, command_ax, edge_ax) = new_figure(3, height=2.3)
    angle_ax.plot(t, setpoint, color=LIMIT, linestyle='--', linewidth=1.0, label='set-point')
    angle_ax.plot(t, angle, color=MEASURED, linewidth=1.2, label='angle')
    angle_ax.set_ylabel('angle (deg)')
    angle_ax.legend(loc='upper right', fontsize=8, frameon=False)
    command_ax.plot(t, command, color=MODEL, linewidth=0.8)
    command_ax.set_ylabel(f'valve v ({command_unit})')
    edge_ax.plot(t, edges[:, 0], color=MEASURED, linewidth=1.4, label='IDZ lower edge')
    edge_ax.plot(t, edges[:, 1], color=MODEL, linewidth=1.4, label='IDZ upper edge')
    edge_ax.set_ylabel(f'IDZ edges ({command_unit})')
    edge_ax.set_xlabel('time (s)')
    edge_ax.legend(loc='center right', fontsize=8, frameon=False)
    for ax in (angle_ax, command_ax, edge_ax):
        ax.axvline(drift, color='black', linestyle=':', linewidth=1.0)
    angle_ax.text(drift, 1.0, f' dead-zone narrows by 0.3 {command_unit}', fontsize=8, va='top',
                  transform=angle_ax.get_xaxis_transform())
    figure.suptitle('Wear, detected and recalibrated by the identifier node', fontsize=11)
    return figure

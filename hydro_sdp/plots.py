"""
Figures in the style of West et al. (2018), drawn with matplotlib's object API.

Figures are built on :class:`matplotlib.figure.Figure` directly (no pyplot
global state), so they can be made from any thread and in tests, and saved
whole or not at all with :func:`save_figure`.

"""

from __future__ import annotations

import io
import os
from pathlib import Path
from typing import Sequence

from hydro_sdp.core.model import JointModel
from hydro_sdp.core.records import Record
from hydro_sdp.files import atomic_write_bytes
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
import numpy as np

#: Colours used throughout: measured data, model, limits.
MEASURED = '#1f4e79'
MODEL = '#d95f02'
LIMIT = '#7f7f7f'


def new_figure(rows: int = 1, *, height: float = 2.6, width: float = 9.0,
               sharex: bool = True) -> tuple[Figure, Sequence]:
    """
    Create a figure with ``rows`` stacked axes sharing the time axis.

    Parameters
    ----------
    rows : int
        Number of stacked subplots.
    height : float
        Height of each subplot, inches.
    width : float
        Figure width, inches.
    sharex : bool
        Whether the subplots share their x axis.

    Returns
    -------
    tuple
        The figure and a list of its axes.

    """
    figure = Figure(figsize=(width, height * rows + 0.6), layout='constrained')
    FigureCanvasAgg(figure)
    axes = figure.subplots(rows, 1, sharex=sharex, squeeze=False)[:, 0]
    for ax in axes:
        ax.grid(True, color='#dddddd', linewidth=0.6)
        ax.set_axisbelow(True)
    return figure, list(axes)


def save_figure(figure: Figure, path: str | os.PathLike[str], *, dpi: int = 130) -> Path:
    """
    Save a figure as PNG, whole or not at all.

    Parameters
    ----------
    figure : Figure
        The figure.
    path : str or PathLike
        Target PNG file.
    dpi : int
        Resolution.

    Returns
    -------
    Path
        The target path.

    """
    buffer = io.BytesIO()
    figure.savefig(buffer, format='png', dpi=dpi)
    return atomic_write_bytes(path, buffer.getvalue())


def _mark_limits(ax, limits: tuple[float, float] | None, label: str) -> None:
    if limits is None:
        return
    for value in limits:
        ax.axhline(value, color=LIMIT, linestyle='--', linewidth=0.9)
    ax.text(1.0, limits[1], f' {label}', transform=ax.get_yaxis_transform(),
            color=LIMIT, fontsize=8, va='center', ha='left', clip_on=False)


def plot_record(record: Record, model: JointModel | None = None, *,
                simulated: np.ndarray | None = None, title: str = '',
                command_unit: str = 'V') -> Figure:
    """
    Angle (upper) and command (lower) against time, as the paper's Fig. 4.

    Parameters
    ----------
    record : Record
        Measured (or simulated) data.
    model : JointModel or None
        Marks end stops and the dead-zone when given.
    simulated : numpy.ndarray or None
        Model response to overlay on the angle, degrees.
    title : str
        Figure title.
    command_unit : str
        Unit of the command, for the axis label.

    Returns
    -------
    Figure
        The figure.

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
    command_ax.set_ylabel(f'command v ({command_unit})')
    command_ax.set_xlabel('time (s)')
    if model is not None:
        _mark_limits(angle_ax, model.angle_limits, 'end stops')
        if model.dead_zone is not None:
            command_ax.axhspan(*model.dead_zone, color=LIMIT, alpha=0.15, linewidth=0)
            command_ax.text(1.0, model.dead_zone[1], ' dead-zone',
                            transform=command_ax.get_yaxis_transform(), color=LIMIT,
                            fontsize=8, va='bottom', ha='left', clip_on=False)
    figure.suptitle(title or f'joint {record.joint}', fontsize=11)
    return figure


def plot_velocity_map(model: JointModel, *, v_range: tuple[float, float] | None = None,
                      title: str = '', command_unit: str = 'V',
                      points: tuple[np.ndarray, np.ndarray] | None = None) -> Figure:
    """
    Angular velocity against steady command, as the paper's Fig. 3.

    Parameters
    ----------
    model : JointModel
        The joint; its map is drawn, with dead-zone and saturation marked.
    v_range : tuple[float, float] or None
        Command range; default: the input limits, or +-5 units.
    title : str
        Figure title.
    command_unit : str
        Unit of the command.
    points : tuple of numpy.ndarray or None
        Per-experiment ``(v, velocity)`` estimates to show as circles.

    Returns
    -------
    Figure
        The figure.

    """
    figure, (ax,) = new_figure(1, height=4.0, width=7.0)
    low, high = v_range or model.input_limits or (-5.0, 5.0)
    v = np.linspace(low, high, 801)
    ax.plot(v, model.rate(v), color=MODEL, linewidth=1.8, label=f'{model.kind} map')
    if points is not None:
        ax.plot(points[0], points[1], 'o', color=MEASURED, markersize=4,
                markerfacecolor='none', label='experiments')
    if model.dead_zone is not None:
        for edge in model.dead_zone:
            ax.axvline(edge, color=LIMIT, linestyle='--', linewidth=0.9)
        ax.axvspan(*model.dead_zone, color=LIMIT, alpha=0.12, linewidth=0, label='dead-zone')
    saturation = getattr(model.static_map, 'saturation_velocity', None)
    if saturation is not None:
        for speed in saturation:
            ax.axhline(speed, color=LIMIT, linestyle=':', linewidth=0.9)
    ax.set_xlabel(f'steady command v ({command_unit})')
    ax.set_ylabel('angular velocity (deg/s)')
    ax.legend(loc='center left', fontsize=8, frameon=False)
    figure.suptitle(title or f'velocity map of joint {model.joint}', fontsize=11)
    return figure


def plot_idz(model: JointModel, idz, control_period: float, *,
             u_limits: tuple[float, float] | None = None,
             v_range: tuple[float, float] | None = None, command_unit: str = 'V') -> Figure:
    """
    IDZ approximation, as the paper's Fig. 6.

    The model's increment per control sample against the steady command, the
    chords the IDZ inverts, the dead-zone edges and the limits of ``u``.

    Parameters
    ----------
    model : JointModel
        The joint.
    idz : InverseDeadZone
        The inverse dead-zone of the controller.
    control_period : float
        Control period, s.
    u_limits : tuple[float, float] or None
        Limits of the controller's ``u``, drawn as dotted lines.
    v_range : tuple[float, float] or None
        Command range to draw; default: to where the model saturates (99 %).
    command_unit : str
        Unit of the command.

    Returns
    -------
    Figure
        The figure.

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
    for edge in (low, high):
        ax.axvline(edge, color=LIMIT, linestyle='--', linewidth=0.9)
    ax.axvspan(low, high, color=LIMIT, alpha=0.12, linewidth=0, label='dead-zone')
    if u_limits is not None:
        for value in u_limits:
            ax.axhline(value, color=LIMIT, linestyle=':', linewidth=1.0)
        ax.text(1.0, u_limits[1], ' u limit', transform=ax.get_yaxis_transform(),
                color=LIMIT, fontsize=8, va='center', ha='left', clip_on=False)
    ax.axhline(0.0, color='black', linewidth=0.6)
    ax.set_xlabel(f'steady command v ({command_unit})')
    ax.set_ylabel(f'increment q (deg per {control_period:g} s sample)')
    ax.legend(loc='upper left', fontsize=8, frameon=False)
    figure.suptitle(f'IDZ approximation of joint {model.joint} '
                    f'(slopes {idz.slopes[0]:.4g}, {idz.slopes[1]:.4g}; beta {idz.beta:g})',
                    fontsize=11)
    return figure


def plot_closed_loop(traces: Sequence, *, title: str = '', command_unit: str = 'V') -> Figure:
    """
    Closed-loop response, as the paper's Fig. 7: angle, u and v against time.

    Parameters
    ----------
    traces : sequence of LoopTrace
        One or more joints' traces.
    title : str
        Figure title.
    command_unit : str
        Unit of the valve command.

    Returns
    -------
    Figure
        The figure.

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
    if several:
        axes[1].axhline(0.0, color='black', linewidth=0.6)
        axes[1].set_ylabel('error y - d (deg)')
    angle_ax.set_ylabel('angle y (deg)')
    angle_ax.legend(loc='lower right', fontsize=8, frameon=False,
                    title='dashed: set-point', title_fontsize=8)
    u_ax.set_ylabel('PIP input u\n(deg/sample)')
    v_ax.set_ylabel(f'valve v ({command_unit})')
    v_ax.set_xlabel('time (s)')
    figure.suptitle(title or 'PIP-IDZ closed loop', fontsize=11)
    return figure


def plot_step_responses(experiments: Sequence, delay: int, dt: float, *,
                        title: str = '') -> Figure:
    """
    Step responses and differenced angles against sample, as the paper's Fig. 1.

    Parameters
    ----------
    experiments : sequence of Experiment
        Experiments; only steps are drawn, each normalised to start at 0.
    delay : int
        Estimated delay, samples, drawn dashed.
    dt : float
        Sample period, s.
    title : str
        Figure title.

    Returns
    -------
    Figure
        The figure.

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


def matplotlib_colormap():
    """Return the diverging colour map used for command levels."""
    from matplotlib import colormaps
    return colormaps['coolwarm']


def plot_gains(points: Sequence, model: JointModel, dt: float, *, rest: float = 0.0,
               command_unit: str = 'V') -> Figure:
    """
    State-dependent gain against command, as the paper's Fig. 2.

    Parameters
    ----------
    points : sequence of LevelSpeed
        Per-experiment gains ``b_tau``.
    model : JointModel
        The identified model; its ``b_tau(v) = dt rate(v) / (v - rest)`` is drawn.
    dt : float
        Sample period, s.
    rest : float
        Rest command.
    command_unit : str
        Unit of the command.

    Returns
    -------
    Figure
        The figure.

    """
    figure, (ax,) = new_figure(1, height=4.0, width=7.0)
    levels = np.array([p.level for p in points if p.level != rest])
    gains = np.array([p.gain * 1.0 for p in points if p.level != rest])
    ax.plot(levels, gains, 'o', color=MEASURED, markerfacecolor='none', markersize=5,
            label='per experiment (RIV)')
    span = max(np.max(np.abs(levels - rest)), 1e-9) if levels.size else 1.0
    v = np.linspace(rest - 1.05 * span, rest + 1.05 * span, 801)
    v = v[np.abs(v - rest) > 1e-9 * span]
    ax.plot(v, dt * model.rate(v) / (v - rest), color=MODEL, linewidth=1.8,
            label=f'{model.kind} model')
    ax.set_xlabel(f'steady command v ({command_unit})')
    ax.set_ylabel('b_tau (deg per sample per unit)')
    ax.legend(loc='upper left', fontsize=8, frameon=False)
    figure.suptitle(f'State-dependent gain of joint {model.joint} (West et al. 2018, Fig. 2)',
                    fontsize=11)
    return figure


SIGNATURE_FEATURES = {
    'dead_zone': 'command', 'velocity_saturation': 'command', 'asymmetry': 'command',
    'time_delay': 'events', 'direction_dependent_delay': 'events', 'valve_lag': 'events',
    'backlash': 'reversals', 'angle_limits': 'angle', 'angle_dependent_velocity': 'angle',
}


def _binned(x: np.ndarray, values: np.ndarray, bins: int = 30):
    edges = np.linspace(np.min(x), np.max(x), bins + 1)
    index = np.clip(np.digitize(x, edges) - 1, 0, bins - 1)
    counts = np.bincount(index, minlength=bins)
    sums = np.bincount(index, weights=values, minlength=bins)
    keep = counts > 5
    return 0.5 * (edges[1:] + edges[:-1])[keep], (sums / np.maximum(counts, 1))[keep]


def _event_average(triggers: np.ndarray, values: np.ndarray, span: int,
                   signs: np.ndarray | None = None):
    # Each event's residual is flipped by the sign of its change, so that rising and
    # falling changes add up instead of cancelling.
    signs = np.ones(triggers.size) if signs is None else signs
    rows = [sign * values[k:k + span] for k, sign in zip(triggers, signs)
            if k + span <= values.size]
    if not rows:
        return np.arange(span), np.zeros(span)
    return np.arange(span), np.mean(rows, axis=0)


def plot_signature(effect: str, features: dict, before: np.ndarray, after: np.ndarray,
                   dt: float) -> Figure:
    """
    Draw the residual signature that named an effect, before and after adding it.

    Parameters
    ----------
    effect : str
        Vocabulary word.
    features : dict
        ``command`` (delayed command), ``angle`` (degrees) and ``speed`` (model
        increments) alongside the residuals.
    before, after : numpy.ndarray
        Velocity residuals (measured minus predicted increments), degrees.
    dt : float
        Sample period, s.

    Returns
    -------
    Figure
        The figure.

    """
    figure, (ax,) = new_figure(1, height=3.8, width=8.0)
    kind = SIGNATURE_FEATURES.get(effect, 'command')
    if kind in ('events', 'reversals'):
        command = features['command']
        if kind == 'events':
            triggers = np.flatnonzero(np.diff(command)) + 1
            signs = np.sign(np.diff(command)[triggers - 1])
            label = 'samples after a delayed command change (signed by the change)'
        else:
            direction = np.sign(features['speed'])
            moving = np.flatnonzero(direction != 0)
            triggers = moving[1:][np.diff(direction[moving]) != 0]
            signs = direction[triggers]
            label = 'samples after a reversal of motion (signed by the new direction)'
        span = int(round(1.0 / dt))
        for values, colour, name in ((before, MODEL, 'before'), (after, MEASURED, 'after')):
            lags, mean = _event_average(triggers, values / dt, span, signs)
            ax.plot(lags, mean, color=colour, linewidth=1.6, label=name)
        ax.set_xlabel(label)
    else:
        x = features['command'] if kind == 'command' else features['angle']
        for values, colour, name in ((before, MODEL, 'before'), (after, MEASURED, 'after')):
            centres, means = _binned(x, values / dt)
            ax.plot(centres, means, 'o-', color=colour, markersize=3, linewidth=1.2, label=name)
        ax.set_xlabel('delayed command' if kind == 'command' else 'joint angle (deg)')
    ax.axhline(0.0, color='black', linewidth=0.6)
    ax.set_ylabel('mean velocity residual (deg/s)')
    ax.legend(loc='best', fontsize=8, frameon=False)
    figure.suptitle(f'Residual signature of {effect}', fontsize=11)
    return figure


def plot_gap(t: np.ndarray, measured: np.ndarray, before: np.ndarray, after: np.ndarray, *,
             title: str = '') -> Figure:
    """
    Measured angle against the model before and after the named effects.

    Parameters
    ----------
    t : numpy.ndarray
        Time, s.
    measured, before, after : numpy.ndarray
        Angles, degrees.
    title : str
        Figure title.

    Returns
    -------
    Figure
        The figure.

    """
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


def plot_ledger(mae_start: float, steps: Sequence) -> Figure:
    """
    Draw the validation MAE after each effect added (the gap ledger).

    Parameters
    ----------
    mae_start : float
        MAE of the model given, degrees.
    steps : sequence of LedgerStep
        The effects added in turn.

    Returns
    -------
    Figure
        The figure.

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


def plot_recalibration(t: np.ndarray, angle: np.ndarray, setpoint: np.ndarray,
                       command: np.ndarray, edges: np.ndarray, drift: float) -> Figure:
    """
    Draw a loop whose dead-zone drifts and whose IDZ the identifier recalibrates.

    Parameters
    ----------
    t : numpy.ndarray
        Time, s.
    angle, setpoint : numpy.ndarray
        Joint angle and set-point, degrees.
    command : numpy.ndarray
        Valve command, V.
    edges : numpy.ndarray
        ``(samples, 2)`` IDZ edges the controller used, V.
    drift : float
        Time the plant's dead-zone moved, s.

    Returns
    -------
    Figure
        The figure.

    """
    figure, (angle_ax, command_ax, edge_ax) = new_figure(3, height=2.3)
    angle_ax.plot(t, setpoint, color=LIMIT, linestyle='--', linewidth=1.0, label='set-point')
    angle_ax.plot(t, angle, color=MEASURED, linewidth=1.2, label='angle')
    angle_ax.set_ylabel('angle (deg)')
    angle_ax.legend(loc='upper right', fontsize=8, frameon=False)
    command_ax.plot(t, command, color=MODEL, linewidth=0.8)
    command_ax.set_ylabel('valve v (V)')
    edge_ax.plot(t, edges[:, 0], color=MEASURED, linewidth=1.4, label='IDZ lower edge')
    edge_ax.plot(t, edges[:, 1], color=MODEL, linewidth=1.4, label='IDZ upper edge')
    edge_ax.set_ylabel('IDZ edges (V)')
    edge_ax.set_xlabel('time (s)')
    edge_ax.legend(loc='center right', fontsize=8, frameon=False)
    for ax in (angle_ax, command_ax, edge_ax):
        ax.axvline(drift, color='black', linestyle=':', linewidth=1.0)
    angle_ax.text(drift, 1.0, ' dead-zone narrows by 0.3 V', fontsize=8, va='top',
                  transform=angle_ax.get_xaxis_transform())
    figure.suptitle('Wear, detected and recalibrated by the identifier node', fontsize=11)
    return figure

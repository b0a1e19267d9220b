"""``hydro-sdp identify``: an SDP model of a joint from recorded bags."""

from __future__ import annotations

import argparse
from dataclasses import replace
import math
from pathlib import Path
from typing import Iterator, TYPE_CHECKING

from hydro_sdp.cli.common import (
    add_bag_options, finite_float, json_number, Outcome, Payload, pieces_note, positive_float,
    read_records_and_topic, table)
from hydro_sdp.cli.progress import ProgressBar
from hydro_sdp.core.model.joint_model import JointModel
from hydro_sdp.io.model_files import save_model
import numpy as np

if TYPE_CHECKING:
    from hydro_sdp.core.identification.held_out import Judgement
    from hydro_sdp.core.identification.identify import Identification

HELP = 'identify a joint model from experiments or routine operation'
DESCRIPTION = """\
Identify a hydraulic joint from recorded bags. From experiments with held
command levels (steps, random levels, full strokes), as West et al. (2018)
section 4:

  1. cut the records into step experiments (command leaves rest, holds, returns)
     and runs, dropping what an end stop clamps; rest is the valve's neutral:
     0 when the commands take both signs, else --rest (or the middle of
     --input-limits), never a command that moves the joint;
  2. estimate the dead time together with a first-order valve lag (fit of the
     differenced angle, checked against motion onsets and cross-correlation);
  3. measure the speed of every command level (Figs. 2 and 3);
  4. fit the static map to the raw angles by regret-regression (--method rr) or by
     the paper's output-error simplex fit (--method oe);
  5. with --kind auto, also fit a monotone piecewise-linear map (a knot at every
     measured level), the second paper's polynomial gain and, when eq. (5)
     loses, a saturating power law (power_sat, convex from the dead-zone), and
     keep the family that predicts held-out experiments best (folds that leave
     out levels inside the measured range), the simpler one when it is within
     its tie band (5 % of its error, or one standard error of its per-fold
     difference): the table, the bands and the reason are printed;
  6. when the runs span the stroke, fit how the speed changes along it
     (effect stroke_geometry); keep it, and the valve lag, only when held-out
     experiments need it by the same rule.

What the data do not pin is printed as a bound: a dead-zone edge below every
command held (with the speed seen at the innermost command and what to record
to pin it), a parameter whose two standard errors exceed it. Runs that stalled
(commanded, not moving, not at a stop) are left out and listed; an end stop
seen on one side only stays in the model.

Routine operation (a closed loop, an operator's joystick: the command changes
every control period and held levels carry under half of the driving) is
identified from the one-step angle increments against the delayed command:
the delay that explains them best, the speed along the command by the SDP
smoother, each map family fitted to the increments and chosen on held-out
pieces; data that never moved the joint one way are refused, naming the
commands never seen.

Commands may be in any unit (volts, percent duty): nothing assumes +-10 V.
Without --input-limits the model's valve range is the range of commands the
records used; end stops given with --angle-limits are written as given, else
those the joint was seen held at. The model file remembers the command topic
read (key command_topic): evaluate and diagnose read bags from it when
--command-topic is not given.

examples:
  hydro-sdp identify steps_bag --out j2_model.yaml --plot-dir figures
  hydro-sdp identify run1 run2 --joint boom --command-topic /boom/cmd --kind pwl
  hydro-sdp identify loop_bag --out j2_from_work.yaml     # a recorded closed loop
"""


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the ``identify`` command to the command line."""
    from hydro_sdp.core.identification.identify import KINDS

    parser = subparsers.add_parser('identify', help=HELP, description=DESCRIPTION,
                                   formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument('bags', nargs='+', metavar='BAG', help='rosbag2 bags of one joint')
    add_bag_options(parser)
    parser.add_argument('--method', choices=('rr', 'oe'), default='rr',
                        help='regret-regression (default) or output-error simplex fit')
    parser.add_argument('--kind', choices=('auto',) + KINDS, default='auto',
                        help='static-map family (default: auto, chosen on held-out data)')
    parser.add_argument('--max-delay', type=positive_float, default=0.5,
                        help='largest delay considered, s (default: 0.5)')
    parser.add_argument('--angle-limits', nargs=2, type=finite_float, metavar=('LOW', 'HIGH'),
                        help='known end stops, deg (default: those seen in the data)')
    parser.add_argument('--input-limits', nargs=2, type=finite_float, metavar=('LOW', 'HIGH'),
                        help='command range of the valve, written to the model (default: '
                             'the range of commands the records used)')
    parser.add_argument('--rest', type=finite_float, metavar='COMMAND',
                        help="the valve's neutral command (default: 0 when the commands take "
                             'both signs, else the middle of --input-limits or a command at '
                             'which the joint stands still)')
    parser.add_argument('--out', help='model file to write (YAML)')
    parser.add_argument('--plot-dir', help='folder for Figs. 1-3 (step responses, gains, speeds; '
                                           'routine operation: gains and speeds)')
    parser.set_defaults(run=run)


def describe(result: Identification) -> Payload:
    """Return the ``--json`` object of an identification."""
    segmentation = result.segmentation
    payload = result.model.to_mapping()
    payload.setdefault('undetermined', {})  # in the JSON always; in the file when not empty
    payload.update({
        'alpha': list(result.alpha) if result.alpha is not None else None,
        'sample_period': result.sample_period,
        'method': result.fit.method,
        'beta': result.fit.beta,
        'standard_errors': result.fit.standard_errors,
        'experiments': {
            'used': len(segmentation.experiments), 'steps': segmentation.steps,
            'runs': segmentation.runs,
            'dropped': [{'t': d.t0, 'reason': d.reason, 'source': d.source}
                        for d in segmentation.dropped],
            'stalled': [{'t': d.t0, 'reason': d.reason, 'source': d.source}
                        for d in segmentation.dropped if d.stalled]},
        'route': result.route,
        'rest': segmentation.rest,
        'end_stops': list(segmentation.end_stops),
        'end_stops_from': _source(result, 'angle'),
        'input_limits_from': _source(result, 'input'),
        'commands_seen': list(result.commands.seen) if result.commands else None,
        'delay_estimates': {'samples': result.delay.samples, 'seconds': result.delay.seconds,
                            'lag': result.delay.lag,
                            'fit': result.delay.fit, 'onset': result.delay.onset,
                            'xcorr': result.delay.xcorr, 'agree': result.delay.agree},
        'noise_std': segmentation.noise_std,
        'comparison': [{'kind': s.kind, 'mae': json_number(s.mae), 'note': s.note}
                       for s in result.comparison],
        'mae': result.mae,
        'family_choice': None if result.family is None else _judgement(result.family),
        'effect_checks': [{'effect': c.effect, 'without': c.without, 'with': c.with_effect,
                           'gain': c.gain, 'kept': c.kept, **_judgement(c.judgement)}
                          for c in result.effect_checks],
    })
    return payload


def run(args: argparse.Namespace) -> Outcome:
    """Run ``identify``."""
    from hydro_sdp.core.identification.identify import identify, IdentifyStage

    records, topic = read_records_and_topic(args.bags, args.joint, args.command_topic)
    with ProgressBar('identify', len(IdentifyStage)) as bar:
        result = identify(
            records, method=args.method, kind=args.kind, max_delay=args.max_delay,
            angle_limits=tuple(args.angle_limits) if args.angle_limits else None,
            input_limits=tuple(args.input_limits) if args.input_limits else None,
            rest=args.rest, progress=bar.update)
    # The model file remembers the topic, so evaluate and diagnose read the same one.
    result = replace(result, model=replace(result.model, command_topic=topic))
    payload = describe(result)
    # Stalled recordings are cut at their gaps on reading: one piece per stretch.
    payload['pieces'] = len(records)
    model = result.model
    if args.out:
        payload['model'] = str(save_model(model, args.out))
    if args.plot_dir:
        payload['plots'] = _plots(result, records, Path(args.plot_dir))
    lines = pieces_note(args.bags, records) + _summary(result)
    bounds = {entry.parameter: entry for entry in model.undetermined}
    rows = [[key, _format(value), _format(result.fit.standard_errors.get(name, math.nan))]
            if name not in bounds else
            [key, f'in [{bounds[name].bound[0]:.4g}, {bounds[name].bound[1]:.4g}]',
             'undetermined']
            for key, value, name in _parameter_rows(model)]
    lines += table(rows, ['parameter', 'value', 'std. error'])
    lines += [entry.describe() for entry in model.undetermined]
    if result.family is not None:
        lines += _family_lines(result)
    if result.route == 'routine':
        lines.append(f'chosen: {model.kind} (least squares on the one-step increments); '
                     f'simulation MAE on 1 s pieces of the runs {result.mae:.4f} deg')
    else:
        lines.append(f'chosen: {model.kind} ({result.fit.method}, beta {result.fit.beta:.3f}); '
                     f'simulation MAE on the experiments {result.mae:.4f} deg')
    lines += [f'held-out check of {check.describe()}' for check in result.effect_checks]
    if model.effect('stroke_geometry') is not None:
        lines.append('speed along the stroke: effect stroke_geometry (see the model file)')
    lines += [f'wrote {path}' for path in payload.get('plots', [])]
    if args.out:
        lines.append(f'wrote {payload["model"]}')
    return Outcome(payload, lines)


def _judgement(judgement: Judgement) -> Payload:
    """Return the JSON of a held-out judgement: the figures the decision followed."""
    return {'candidates': list(judgement.names),
            'pooled': [json_number(e) for e in judgement.pooled],
            'folds': [[json_number(e) for e in row] for row in judgement.errors],
            'weights': list(judgement.weights),
            'bands': [json_number(b) for b in judgement.bands],
            'chosen': judgement.names[judgement.chosen] if judgement.chosen >= 0 else None,
            'rule': judgement.rule()}


def _family_lines(result: Identification) -> list[str]:
    """Return the family table with the rule and why the family was chosen."""
    judgement = result.family
    assert judgement is not None
    notes: dict[str, str] = {s.kind: s.note for s in result.comparison}
    rows = [[name, _format(pooled), _format(band), notes.get(name, '')[:50]]
            for name, pooled, band in zip(judgement.names, judgement.pooled, judgement.bands)]
    return (['held-out error by map family (mean absolute error over 2 s windows of the '
             f'held-out experiments, {len(judgement.weights)} folds; simplest first):']
            + table(rows, ['kind', 'error (deg)', 'tie band', 'note'])
            + [f'rule: {judgement.rule()}', f'chosen: {judgement.verdict()}'])


def _summary(result: Identification) -> list[str]:
    """Return the lines on what was read: experiments or runs, rest, stops, range, delay."""
    segmentation, model, delay = result.segmentation, result.model, result.delay
    common = (f'{len(segmentation.dropped)} segments dropped, sample period '
              f'{result.sample_period:g} s, noise {segmentation.noise_std:.3g} deg')
    if result.route == 'routine':
        lines = [f'joint {model.joint}: routine operation (few held levels), '
                 f'{len(segmentation.experiments)} runs, {common}']
    else:
        lines = [f'joint {model.joint}: {len(segmentation.experiments)} experiments '
                 f'({segmentation.steps} steps, {segmentation.runs} runs), {common}']
    for dropped in segmentation.dropped[:5]:
        lines.append(f'  dropped {dropped.since_start:.2f} s from the start: {dropped.reason}')
    # Every stall is listed: a load held the joint, and its runs say nothing of the valve.
    lines += [f'  {d.source or "record"} at {d.since_start:.2f} s: {d.reason}'
              for d in segmentation.dropped[5:] if d.stalled]
    lines.append(f'rest command {segmentation.rest:g}; end stops {_stops(result)}')
    if result.commands is not None:
        low, high = result.commands.seen
        lines.append(f'commands seen {low:.4g} .. {high:.4g}; valve range '
                     f'{_pair(model.input_limits)} '
                     + ('(given)' if result.commands.input_limits_from == 'given' else
                        '(the commands seen; --input-limits gives the whole range)'))
    if result.route == 'routine':
        lines.append(f'delay: {delay.samples} samples = {delay.seconds:g} s (the increments '
                     f'against the delayed command; linear cross-correlation {delay.xcorr}); '
                     'no valve lag from routine operation')
    else:
        lines.append(f'delay: {delay.samples} samples = {delay.seconds:g} s, valve lag '
                     f'{delay.lag:g} s (fit; onset {delay.onset}, cross-correlation '
                     f'{delay.xcorr})')
    return lines


def _plots(result: Identification, records: list, folder: Path) -> list[str]:
    """Draw Figs. 1-3 (routine operation: 2 and 3) into ``folder``; return the files."""
    from hydro_sdp.plots import (
        plot_gains, plot_step_responses, plot_velocity_map, save_figure)

    model, segmentation = result.model, result.segmentation
    moving = [p for p in result.points if p.level != segmentation.rest]
    written = []
    routine = result.route == 'routine'
    # Routine operation's points are the SDP smoother's curve itself.
    label = 'SDP smoother along the delayed command' if routine else None
    if not routine:
        written.append(save_figure(plot_step_responses(
            segmentation.experiments, result.delay.samples, result.sample_period),
            folder / 'step_responses.png'))
    written.append(save_figure(plot_gains(
        result.points, model, result.sample_period, rest=segmentation.rest,
        measured=() if routine else _measured_gain(records, result),
        points_label=label or 'per experiment (RIV)'), folder / 'gains.png'))
    written.append(save_figure(plot_velocity_map(
        model, v_range=_command_range(result),
        points=(np.array([p.level for p in moving]), np.array([p.speed for p in moving])),
        title=f'Velocity map of joint {model.joint} (West et al. 2018, Fig. 3)',
        points_label=label or 'experiments'), folder / 'velocity_map.png'))
    return [str(path) for path in written]


def _measured_gain(records: list, result: Identification) -> tuple:
    """Return the gain along the delayed command by the SDP analysis, for the gains figure."""
    from hydro_sdp.core.errors import HydroSdpError
    from hydro_sdp.core.identification.state_dependence import analyse

    dt = result.sample_period
    try:
        # Model (2) of the paper has no lag: its delay is the dead time plus the lag.
        analysis = analyse(records, states=['command'], rest=result.segmentation.rest,
                           delay=result.delay.samples + int(round(result.delay.lag / dt)),
                           replicates=0)
    except HydroSdpError:
        return ()       # a figure without the curve rather than no figure
    return tuple(analysis.dependence('command', parameter='b'))


def _source(result: Identification, which: str) -> str | None:
    if result.commands is None:
        return None
    return result.commands.angle_limits_from if which == 'angle' else \
        result.commands.input_limits_from


def _stops(result: Identification) -> str:
    stops = result.segmentation.end_stops
    shown = ', '.join('-' if stop is None else f'{stop:.2f} deg' for stop in stops)
    if _source(result, 'angle') == 'given':
        return f'given {shown} (--angle-limits)'
    if all(stop is None for stop in stops):
        return 'none seen (the joint was never held against a stop)'
    return f'seen {shown}'


def _pair(limits: tuple[float, float] | None) -> str:
    return '-' if limits is None else f'[{limits[0]:.4g}, {limits[1]:.4g}]'


def _command_range(result: Identification) -> tuple[float, float]:
    levels = [p.level for p in result.points]
    span = max(levels) - min(levels)
    return min(levels) - 0.1 * span, max(levels) + 0.1 * span


def _parameter_rows(model: JointModel) -> Iterator[tuple[str, float, str]]:
    mapping = model.static_map.to_mapping()
    for key, value in mapping.items():
        if isinstance(value, list):
            for i, item in enumerate(value):
                yield f'{key}[{i}]', item, f'{key}[{i}]'
        else:
            yield key, value, key
    yield 'delay', model.delay, 'delay'


def _format(value: float) -> str:
    return '-' if value is None or not math.isfinite(value) else f'{value:.5g}'

"""``hydro-sdp sdp``: let the data show how a joint's parameters depend on its states."""

from __future__ import annotations

import argparse
import math
from pathlib import Path
from typing import Iterable, TYPE_CHECKING

from hydro_sdp.cli.common import (
    add_bag_options, json_number, Outcome, Payload, pieces_note, positive_float, read_records,
    table)
from hydro_sdp.cli.progress import ProgressBar

if TYPE_CHECKING:
    from hydro_sdp.core.identification.state_dependence import SdpAnalysis, StateDependence

HELP = 'estimate how a parameter depends on each state, without assuming its shape (SDP)'
STATE_NAMES = ('command', 'angle', 'since_change', 'others_speed', 'load', 'reversals')
DESCRIPTION = """\
The non-parametric stage of the SDP method (Young, McKenna and Bruun 2001;
CAPTAIN's sdp): the samples are sorted by a candidate state, the parameter is
estimated along that order as a random walk by the fixed-interval smoother,
its noise variance ratio (NVR) by maximum likelihood; several parameters are
back-fitted together. Nothing assumes a map family or an effect's form.

Without --model: the SDP-ARX model of the joint (the first paper's step 2),

    y_k = -a1 y_{k-1} + b{state} (v_{k-tau} - rest),

b split by the direction of the drive, tau from the data (dead time plus the
valve lag). A first-order integrator has a1 = -1 (printed with its standard
error and its NVR along the angle: 0 means constant).
With --model: what the model misses, against each state: the ratio of the
measured to the model's angle increment where the model moves (1: right),
per direction, and the increment residual (0: right).

States (--states, comma-separated; default all the records can give):
  command       the delayed command v_{k-tau}
  angle         the angle the increment starts from (each direction its curve)
  since_change  time since the delayed command last changed, s
  others_speed  the other joints' summed speed, from the JointState, deg/s
  load          the --load-topic signal (a cylinder pressure, say)
  reversals     travel since the motion last reversed (the model's, with
                --model), deg: play shows as motion lost right after it

Increments the joint cannot make are left out, with their count: held at an
end stop while the command drives into it, resting at a stop, or stalled
(driven, not moving, away from the stops).

Each state is first weighed alone; the one that explains most comes first, and
every other is weighed by what it adds to it. For each: its share of the
constant-parameter model's squared residual (held out: predicted on tenths of
the data it was not fitted to), its NVR (0: no dependence) and whether the
dependence is significant (p <= 0.01 by a bootstrap that flips the signs of
whole runs of held commands, so that neither the residuals' autocorrelation
nor one run's own error passes for a dependence). --plot-dir draws each
parameter against each state with +-2 standard-error bands, and the shares.

examples:
  hydro-sdp sdp steps_bag --joint j2 --plot-dir sdp_figures
  hydro-sdp sdp arm_and_boom --joint arm --model arm.yaml --states angle,others_speed
  hydro-sdp sdp heavy light --model boom.yaml --load-topic /boom/pressure --json
"""


def _states(text: str) -> tuple[str, ...]:
    names = tuple(name.strip() for name in text.split(',') if name.strip())
    unknown = [name for name in names if name not in STATE_NAMES]
    if unknown or not names:
        raise argparse.ArgumentTypeError(
            f"unknown state {unknown[0]!r}; choose from {', '.join(STATE_NAMES)}"
            if unknown else 'name at least one state')
    if len(set(names)) != len(names):
        raise argparse.ArgumentTypeError(f'a state is named twice in {text!r}')
    return names


def _replicates(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f'expected a whole number, got {text!r}') from None
    if value < 19:
        raise argparse.ArgumentTypeError(f'need at least 19 replicates, got {value}')
    return value


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the ``sdp`` command to the command line."""
    parser = subparsers.add_parser('sdp', help=HELP, description=DESCRIPTION,
                                   formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument('bags', nargs='+', metavar='BAG', help='rosbag2 bags of one joint')
    add_bag_options(parser)
    parser.add_argument('--model', help='model file: analyse what it misses (default: the '
                                        'SDP-ARX model of the data)')
    parser.add_argument('--states', type=_states, default=STATE_NAMES, metavar='S,...',
                        help='candidate states, comma-separated (default: all)')
    parser.add_argument('--load-topic', metavar='TOPIC',
                        help="Float64 topic of a measured load, the state 'load' (default: "
                             "the model file's load_topic, if any)")
    parser.add_argument('--max-delay', type=positive_float, default=0.5,
                        help='largest delay considered without --model, s (default: 0.5)')
    parser.add_argument('--irw', action='store_true',
                        help='integrated random walks (smoother curves; zero NVR then means '
                             "a line in the state's rank, not a constant)")
    parser.add_argument('--replicates', type=_replicates, default=199,
                        help='bootstrap replicates of each test (default: 199)')
    parser.add_argument('--plot-dir', help='folder for the figures')
    parser.set_defaults(run=run)


def _entry(entry: StateDependence) -> dict[str, object]:
    grid, estimate, se = entry.grid()
    return {'state': entry.state, 'direction': entry.direction, 'parameter': entry.parameter,
            'share': entry.share, 'nvr': entry.nvr, 'significant': bool(entry.significant),
            'p_value': json_number(entry.p_value), 'grid': grid, 'estimate': estimate,
            'se': se, 'constant': entry.constant, 'samples': entry.samples,
            'given': entry.given}


def describe(analysis: SdpAnalysis) -> Payload:
    """Return the ``--json`` object of an analysis (docs/interfaces.md)."""
    a1 = analysis.a1
    return {
        'target': analysis.target,
        'samples': analysis.samples,
        'a1': None if a1 is None else {'mean': a1.mean, 'se': a1.se, 'nvr': a1.nvr},
        'states': [_entry(entry) for entry in analysis.states],
        'residual': [_entry(entry) for entry in analysis.residual],
        'delay': {'samples': analysis.delay,
                  'seconds': analysis.delay * analysis.sample_period},
        'sample_period': analysis.sample_period,
        'rest': analysis.rest,
        'skipped': [{'state': state, 'reason': reason} for state, reason in analysis.skipped],
        'left_out': [{'reason': reason, 'rows': rows}
                     for reason, rows in analysis.left_out.items()],
        'alone': dict(analysis.alone),
    }


def run(args: argparse.Namespace) -> Outcome:
    """Run ``sdp``."""
    from hydro_sdp.core.identification.state_dependence import analyse
    from hydro_sdp.io.model_files import load_model

    model = load_model(args.model) if args.model else None
    joint = args.joint or (model.joint if model is not None else None)
    load_topic = args.load_topic or (model.load_topic if model is not None else None)
    records = read_records(args.bags, joint, args.command_topic,
                           preferred_topic=model.command_topic if model is not None else None,
                           load_topic=load_topic, others=True)
    states = [name for name in args.states if name != 'load' or load_topic]
    if not states:
        raise _no_states(args.states)
    # Every state is fitted alone, then with the first; the residual doubles that, a1 adds one.
    fits = 2 * len(states) * (2 if model is not None else 1) + (model is None)
    with ProgressBar('sdp', fits) as bar:
        done = [0]

        def tick(name: str) -> None:
            bar.update(done[0])
            done[0] += 1
        analysis = analyse(records, model=model, states=states, max_delay=args.max_delay,
                           kind='irw' if args.irw else 'rw', replicates=args.replicates,
                           progress=tick)
    payload = describe(analysis)
    skipped = [(name, 'no --load-topic') for name in args.states if name not in states]
    payload['skipped'] += [{'state': state, 'reason': reason} for state, reason in skipped]
    if args.plot_dir:
        payload['plots'] = _plots(analysis, Path(args.plot_dir))
    return Outcome(payload, pieces_note(args.bags, records) + _lines(analysis, skipped, payload))


def _no_states(asked: tuple[str, ...]) -> Exception:
    from hydro_sdp.core.errors import ConfigurationError
    return ConfigurationError(f"no state to analyse: {', '.join(asked)} needs --load-topic")


def _plots(analysis: SdpAnalysis, folder: Path) -> list[str]:
    from hydro_sdp.plots.figures import save_figure
    from hydro_sdp.plots.sdp import plot_shares, plot_state

    written = [str(save_figure(plot_shares(analysis), folder / 'sdp_shares.png'))]
    for state in analysis.analysed:
        written.append(str(save_figure(plot_state(analysis, state),
                                       folder / f'sdp_{state}.png')))
    return written


def _lines(analysis: SdpAnalysis, skipped: list[tuple[str, str]],
           payload: Payload) -> list[str]:
    what = ('SDP-ARX model y_k = -a1 y_{k-1} + b (v_{k-tau} - rest)' if analysis.target == 'arx'
            else 'measured / model increment (ratio) and increment residual')
    lines = [f'{what}: {analysis.samples} samples, delay {analysis.delay} samples '
             f'({analysis.delay * analysis.sample_period:.3g} s), rest {analysis.rest:g}']
    for reason, rows in analysis.left_out.items():
        lines.append(f'left out {rows} increments {reason}')
    if analysis.a1 is not None:
        a1 = analysis.a1
        lines.append(f'a1 = {a1.mean:.5f} +- {a1.se:.1e} (NVR along the angle {a1.nvr:.3g}; '
                     '-1: an integrator)')
    lines += _table(analysis.states, 'gain' if analysis.target == 'arx' else 'ratio')
    lines.append(_alone(analysis, ''))
    if analysis.residual:
        lines.append('increment residual:')
        lines += _table(analysis.residual, 'residual')
        lines.append(_alone(analysis, 'residual '))
    for state, reason in list(analysis.skipped) + skipped:
        lines.append(f'  {state} not analysed: {reason}')
    if analysis.states:
        first = analysis.states[0]
        verdict = 'significantly' if first.significant else 'not significantly'
        lines.append(f'first: {first.parameter} depends {verdict} on {first.state} '
                     f'({first.direction}), share {100 * first.share:.1f} %')
    for path in payload.get('plots', []):
        lines.append(f'wrote {path}')
    return lines


def _alone(analysis: SdpAnalysis, prefix: str) -> str:
    """Return the share each state's gains remove alone: the evidence for the first state."""
    shares = [f'{key[len(prefix):]} {100 * share:.1f} %' for key, share in analysis.alone.items()
              if key.startswith(prefix) and (prefix or not key.startswith('residual '))]
    return ('  alone (first: the largest; within 2 % of it, the first listed): '
            + ', '.join(shares))


def _table(entries: Iterable[StateDependence], what: str) -> list[str]:
    rows = [[e.state, e.direction, f'{100 * e.share:.1f}', f'{e.nvr:.3g}',
             '-' if not math.isfinite(e.p_value) else f'{e.p_value:.3f}',
             'yes' if e.significant else 'no',
             f'{float(min(e.estimate)):.4g} .. {float(max(e.estimate)):.4g}']
            for e in entries]
    return table(rows, ['state', 'direction', 'share %', 'NVR', 'p', 'significant',
                        f'{what} range'])

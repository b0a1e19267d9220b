"""``hydro-sdp evaluate``: Table 2 of West et al. on recorded bags."""

from __future__ import annotations

import argparse
from pathlib import Path

from hydro_sdp.cli.common import (
    add_bag_options, json_number, Outcome, pieces_note, read_records, table)
from hydro_sdp.io.model_files import load_model

HELP = 'simulation error of a model and its SDP-DZ and linear benchmarks (Table 2)'
DESCRIPTION = """\
Hold a model against recorded runs, as Table 2 of West et al. (2018): each run is
simulated with its measured commands from its measured angle once the delayed
commands are known, and the mean absolute error (deg) is given for

  model    the model file as it is
  sdp_dz   its SDP-DZ linearisation: chords from the dead-zone edges to where
           the speed reaches two thirds of saturation (eq. 6), same delay and
           end stops
  linear   the linear integrator of eq. (2), its gain optimised for each run

Two means are given: the mean over runs (each run counts once, Table 2; JSON
"mae") and the time-weighted mean (each sample counts once, so long runs weigh
more; JSON "mae_time_weighted").

example:
  hydro-sdp evaluate run1 run2 run3 --model j2_model.yaml --plot-dir figures
"""


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the ``evaluate`` command to the command line."""
    parser = subparsers.add_parser('evaluate', help=HELP, description=DESCRIPTION,
                                   formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument('bags', nargs='+', metavar='BAG', help='evaluation bags')
    parser.add_argument('--model', required=True, help='model file')
    add_bag_options(parser)
    parser.add_argument('--load-topic', metavar='TOPIC',
                        help='Float64 topic of a measured load, for a model whose '
                             'load_dependence was fitted on one (default: the model '
                             "file's load_topic)")
    parser.add_argument('--plot-dir', help='folder for a Fig. 4 style plot of each run')
    parser.set_defaults(run=run)


def run(args: argparse.Namespace) -> Outcome:
    """Run ``evaluate``."""
    from hydro_sdp.core.identification.evaluation import (
        AVERAGES, evaluate, mean_errors, simulated_angles)

    model = load_model(args.model)
    # Without --command-topic the bags are read from the topic the model remembers.
    # With the other joints and the load, so flow_sharing and load_dependence act as in
    # diagnose.
    records = read_records(args.bags, args.joint or model.joint, args.command_topic,
                           preferred_topic=model.command_topic,
                           load_topic=args.load_topic or model.load_topic, others=True)
    scores = evaluate(records, model)
    # A bag with gaps in its time stamps is read as several pieces, one row each.
    rows = [{'bag': record.source, 'samples': s.samples, 'model': s.model,
             'sdp_dz': json_number(s.sdp_dz), 'linear': s.linear, 'linear_gain': s.linear_gain,
             'stalled': s.stalled}
            for record, s in zip(records, scores)]
    means = mean_errors(scores)
    mean = {key: json_number(value) for key, value in means['per_record'].items()}
    weighted = {key: json_number(value) for key, value in means['time_weighted'].items()}
    payload = {'mae': mean, 'mae_time_weighted': weighted,
               'mae_averaging': {'mae': AVERAGES['per_record'],
                                 'mae_time_weighted': AVERAGES['time_weighted']},
               'records': rows, 'model_file': args.model, 'pieces': len(records)}
    if args.plot_dir:
        from hydro_sdp.plots import plot_record, save_figure

        folder = Path(args.plot_dir)
        payload['plots'] = []
        for index, record in enumerate(records, start=1):
            figure = plot_record(record, model, simulated=simulated_angles(model, record),
                                 title=f'Model evaluation, run {index} (West et al. 2018, '
                                       'Fig. 4)')
            payload['plots'].append(str(save_figure(figure, folder / f'evaluation_{index}.png')))
    lines = pieces_note(args.bags, records)
    lines += [f'mean absolute simulation error (deg) of {args.model} and its benchmarks:']
    lines += table([[Path(r['bag']).name, f"{r['model']:.4f}", _format(r['sdp_dz']),
                     f"{r['linear']:.4f}"] for r in rows] +
                   [['mean over runs', _format(mean['model']), _format(mean['sdp_dz']),
                     _format(mean['linear'])],
                    ['time-weighted', _format(weighted['model']), _format(weighted['sdp_dz']),
                     _format(weighted['linear'])]],
                   ['run', 'model', 'SDP-DZ', 'linear'])
    lines.append('mean over runs: each run counts once (Table 2); time-weighted: each sample '
                 'counts once')
    lines += [f'stalled: {Path(r["bag"]).name} held still for {r["stalled"]:.3g} s while the '
              'model moved it, away from any stop; left out of its scores'
              for r in rows if r['stalled'] > 0.0]
    lines += [f'wrote {path}' for path in payload.get('plots', [])]
    return Outcome(payload, lines)


def _format(value: float | None) -> str:
    return '-' if value is None else f'{value:.4f}'

"""``hydro-sdp diagnose``: name what a model misses, add it, show the gap shrink."""

from __future__ import annotations

import argparse
from pathlib import Path

from hydro_sdp.cli.common import add_bag_options, json_number, Outcome, read_records, table
from hydro_sdp.cli.progress import ProgressBar
from hydro_sdp.core.diagnose import (
    diagnose, Diagnosis, runs_of, simulate_record, velocity_residuals, VOCABULARY)
from hydro_sdp.core.simulation import speed_profile
from hydro_sdp.files import atomic_write_text, dump_model, load_model, save_model
from hydro_sdp.plots import plot_gap, plot_ledger, plot_signature, save_figure
import numpy as np

HELP = 'find where a model and the data disagree, name the missing effect, add it'
DESCRIPTION = f"""\
Hold a model against measured bags, name what it misses and add it.

The measured commands are replayed through the model; the velocity residual
(measured increments against the model's one-step predictions) localises the
disagreement. Every effect of the vocabulary is added in turn and fitted:

  {', '.join(VOCABULARY)}

An effect is named when it removes a significant share of the residual (block-
paired t-test over one-second blocks, t > 3, at least 2 %), the largest first;
it is kept only if the simulation error on the validation bags shrinks; the
search repeats until nothing significant is left. `none` when the model already
explains the data within the noise. The augmented model is a normal model file.

example:
  hydro-sdp diagnose run1 run2 --model j2_model.yaml --validation run3 \\
      --out j2_augmented.yaml --report diagnosis
"""


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the ``diagnose`` command to the command line."""
    parser = subparsers.add_parser('diagnose', help=HELP, description=DESCRIPTION,
                                   formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument('bags', nargs='+', metavar='BAG', help='measured bags (estimation)')
    parser.add_argument('--model', required=True, help='model file to hold against them')
    parser.add_argument('--validation', nargs='+', metavar='BAG', default=[],
                        help='held-out bags for the MAE before and after (default: the '
                             'estimation bags)')
    add_bag_options(parser)
    parser.add_argument('--iterations', type=int, default=4,
                        help='most effects added (default: 4)')
    parser.add_argument('--out', help='augmented model file to write')
    parser.add_argument('--report', help='folder for figures and summary.md')
    parser.set_defaults(run=run)


def describe(result: Diagnosis) -> dict:
    """Return the ``--json`` object of a diagnosis."""
    return {
        'effect': result.effect,
        'candidates': [{'effect': c.effect, 'applicable': c.applicable, 'gain': c.gain,
                        't': json_number(c.t), 'significant': c.significant,
                        'parameters': c.parameters, 'evidence': c.evidence}
                       for c in result.candidates],
        'ledger': [{'effect': s.effect, 'parameters': s.parameters,
                    'mae_before': s.mae_before, 'mae_after': s.mae_after}
                   for s in result.ledger],
        'mae_before': result.mae_before,
        'mae_after': result.mae_after,
        'model': result.model.to_mapping(),
    }


def write_report(folder: Path, result: Diagnosis, model, records, validation) -> list[str]:
    """Write the figures and summary.md of a diagnosis; return the figure paths."""
    checks = runs_of(validation or records, model, 0.5)
    run = checks[0]
    record = run.record
    figures = [save_figure(plot_gap(record.t[run.start:], record.y[run.start:],
                                    simulate_record(model, run)[run.start:],
                                    simulate_record(result.model, run)[run.start:],
                                    title='Validation run: model given and augmented'),
                           folder / 'gap.png'),
               save_figure(plot_ledger(result.mae_before, result.ledger), folder / 'ledger.png')]
    if result.ledger:
        first = result.ledger[0].effect
        estimation = runs_of(records, model, 0.5)[0]
        data = estimation.record
        start = estimation.start
        delay = model.delay_samples(estimation.dt)
        speed = speed_profile(model, data.v, estimation.dt, v_before=float(data.v[0]))
        features = {'command': data.v[np.maximum(np.arange(start + 1, len(data)) - delay, 0)],
                    'angle': data.y[start:-1], 'speed': speed[start + 1:]}
        before = velocity_residuals(model, [estimation])[0]
        after = velocity_residuals(result.model, [estimation])[0]
        figures.append(save_figure(plot_signature(first, features, before, after,
                                                  estimation.dt), folder / 'signature.png'))
    rows = [f'| {c.effect} | {"yes" if c.significant else "no"} | {100 * c.gain:.1f} | '
            f'{c.t:.1f} | {c.evidence} |' for c in result.candidates if c.applicable]
    ledger = [f'| {i} | {s.effect} | {s.mae_before:.4g} | {s.mae_after:.4g} |'
              for i, s in enumerate(result.ledger, start=1)]
    summary = '\n'.join([
        '# Discrepancy report', '',
        f'**Named effect: `{result.effect}`.** Validation MAE {result.mae_before:.4g} deg '
        f'before, {result.mae_after:.4g} deg after '
        f'({len(result.ledger)} effect{"s" if len(result.ledger) != 1 else ""} added).', '',
        '## Gap ledger', '', '| step | effect | MAE before (deg) | MAE after (deg) |',
        '|---|---|---|---|', *(ledger or ['| - | none | - | - |']), '',
        '## Candidates (first round)', '',
        'Share of the squared velocity residual each effect removes, and the block-paired t '
        'statistic (significant: t > 3 and at least 2 %).', '',
        '| effect | significant | gain (%) | t | evidence |', '|---|---|---|---|---|', *rows,
        '', '## Figures', '', *[f'![{Path(f).stem}]({Path(f).name})' for f in figures], '',
        '## Augmented model', '', '```yaml', dump_model(result.model).rstrip(), '```', ''])
    atomic_write_text(folder / 'summary.md', summary)
    return [str(f) for f in figures] + [str(folder / 'summary.md')]


def run(args: argparse.Namespace) -> Outcome:
    """Run ``diagnose``."""
    model = load_model(args.model)
    records = read_records(args.bags, args.joint or model.joint, args.command_topic)
    validation = read_records(args.validation, args.joint or model.joint,
                              args.command_topic) if args.validation else []
    effects = list(VOCABULARY)
    with ProgressBar('diagnose', len(effects) * args.iterations) as bar:
        done = [0]

        def tick(name: str) -> None:
            done[0] += 1
            bar.update(done[0])
        result = diagnose(records, model, validation=validation or None,
                          max_iterations=args.iterations, progress=tick)
    payload = describe(result)
    if args.out:
        payload['model_file'] = str(save_model(result.model, args.out))
    if args.report:
        payload['report'] = write_report(Path(args.report), result, model, records, validation)
    lines = [f'named effect: {result.effect}; validation MAE {result.mae_before:.4g} -> '
             f'{result.mae_after:.4g} deg']
    if result.ledger:
        lines += table([[str(i), s.effect, f'{s.mae_before:.4g}', f'{s.mae_after:.4g}',
                         ', '.join(f'{k}={_short(v)}' for k, v in s.parameters.items())]
                        for i, s in enumerate(result.ledger, start=1)],
                       ['step', 'effect', 'MAE before', 'MAE after', 'parameters'])
    lines.append('candidates (first round):')
    lines += table([[c.effect, 'yes' if c.significant else 'no', f'{100 * c.gain:.1f}',
                     f'{c.t:.1f}', c.evidence[:70]] for c in result.candidates if c.applicable],
                   ['effect', 'significant', 'gain %', 't', 'evidence'])
    if args.out:
        lines.append(f'wrote {payload["model_file"]}')
    return Outcome(payload, lines)


def _short(value) -> str:
    if isinstance(value, float):
        return f'{value:.4g}'
    if isinstance(value, list):
        return '[' + ', '.join(_short(v) for v in value) + ']'
    return str(value)

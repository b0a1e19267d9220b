"""``hydro-sdp demo``: the pipeline on the built-in BROKK J2 joint."""

from __future__ import annotations

import argparse
from pathlib import Path

from hydro_sdp.bags import write_bag
from hydro_sdp.cli.common import Outcome, table
from hydro_sdp.cli.progress import ProgressBar
from hydro_sdp.cli.simulate import experiment_record
from hydro_sdp.files import atomic_write_text, default_model_path, load_model
from hydro_sdp.plots import plot_record, plot_velocity_map, save_figure

HELP = 'run the pipeline on the built-in BROKK J2 joint and write a report folder'
DESCRIPTION = """\
Run the hydro_sdp pipeline on the built-in BROKK J2 joint (West et al. 2018):
simulate step and random-level experiments, record them as rosbag2 bags and
draw them. The report folder gets the bags, PNG figures and summary.md.

example:
  hydro-sdp demo --out demo_output
"""


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the ``demo`` command to the command line."""
    parser = subparsers.add_parser('demo', help=HELP, description=DESCRIPTION,
                                   formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument('--out', default='demo_output',
                        help='report folder (default: demo_output)')
    parser.add_argument('--seed', type=int, default=1, help='random seed (default: 1)')
    parser.add_argument('--short', action='store_true',
                        help='shorter experiments, for a quick check')
    parser.set_defaults(run=run)


def run(args: argparse.Namespace) -> Outcome:
    """Run ``demo``."""
    out = Path(args.out)
    figures = out / 'figures'
    model = load_model(default_model_path())
    stages = 4
    with ProgressBar('demo', stages) as bar:
        steps = experiment_record(model, 'steps', seed=args.seed,
                                  duration=30.0 if args.short else None)
        steps_bag = write_bag(out / 'steps_bag', [steps])
        bar.update(1)
        random = experiment_record(model, 'random', seed=args.seed,
                                   duration=30.0 if args.short else 120.0)
        random_bag = write_bag(out / 'random_bag', [random])
        bar.update(2)
        save_figure(plot_record(steps, model, title='J2 step experiments (simulated)'),
                    figures / 'steps.png')
        save_figure(plot_record(random, model, title='J2 random-level run (simulated)'),
                    figures / 'random.png')
        bar.update(3)
        save_figure(plot_velocity_map(model, v_range=(-6.0, 6.0),
                                      title='J2 velocity map (West et al. 2018, Fig. 3)'),
                    figures / 'velocity_map.png')
        bar.update(4)
    rows = [['steps', str(steps_bag), str(len(steps)), f'{steps.duration:.1f}'],
            ['random', str(random_bag), str(len(random)), f'{random.duration:.1f}']]
    lines = table(rows, ['program', 'bag', 'samples', 'seconds'])
    summary = '\n'.join([
        '# hydro_sdp demo: BROKK J2',
        '',
        f'Model: `{default_model_path()}` (kind {model.kind}, delay {model.delay} s, '
        f'dead-zone {list(model.dead_zone or [])} V).',
        '',
        '## Experiments',
        '',
        '| program | bag | samples | seconds |',
        '|---|---|---|---|',
        *[f'| {r[0]} | `{Path(r[1]).name}` | {r[2]} | {r[3]} |' for r in rows],
        '',
        '## Figures',
        '',
        '![steps](figures/steps.png)',
        '![random](figures/random.png)',
        '![velocity map](figures/velocity_map.png)',
        '',
    ])
    atomic_write_text(out / 'summary.md', summary)
    payload = {'summary': {'out': str(out), 'bags': {'steps': str(steps_bag),
                                                     'random': str(random_bag)},
                           'samples': {'steps': len(steps), 'random': len(random)},
                           'figures': sorted(str(p) for p in figures.glob('*.png'))}}
    return Outcome(payload, lines + [f'report: {out / "summary.md"}'])

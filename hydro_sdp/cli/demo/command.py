"""``hydro-sdp demo``: the pipeline on the built-in BROKK J2 joint."""

from __future__ import annotations

import argparse
from pathlib import Path

from hydro_sdp.cli.common import Outcome
from hydro_sdp.cli.progress import ProgressBar
from hydro_sdp.io.atomic import atomic_write_text
from hydro_sdp.io.model_files import default_model_path

HELP = 'run the pipeline on the built-in BROKK J2 joint and write a report folder'
DESCRIPTION = """\
Run the hydro_sdp pipeline on the built-in BROKK J2 joint (West et al. 2018):
simulate step and random-level experiments and record them as rosbag2 bags,
identify the joint from the step bag and evaluate it on the random runs (Table
2), design the PIP-IDZ controller from the identified model, run it in closed
loop on set-point steps, run two LUCIE-like excavator joints along ramps and
drive their bucket tip along a straight line (path error in mm). The report
folder gets the bags, PNG figures in the style of the papers' and summary.md.

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
    # The stages draw figures: matplotlib is loaded only when the demo runs.
    from hydro_sdp.cli.demo.report import Report
    from hydro_sdp.cli.demo.stages import STAGES

    report = Report(Path(args.out), args.short, args.seed)
    with ProgressBar('demo', len(STAGES)) as bar:
        for done, (_, stage) in enumerate(STAGES, start=1):
            stage(report)
            bar.update(done)
    summary = '\n'.join(['# hydro_sdp demo: BROKK J2', '',
                         f'Model: `{default_model_path()}`.', ''] + report.sections)
    atomic_write_text(report.out / 'summary.md', summary)
    payload = {'summary': {'out': str(report.out), **report.payload,
                           'figures': sorted(str(p) for p in
                                             (report.out / 'figures').glob('*.png'))}}
    return Outcome(payload, report.lines + ['', f'report: {report.out / "summary.md"}'])

"""``hydro-sdp import``: CSV logs of a joint written as bags the other commands read."""

from __future__ import annotations

import argparse
from pathlib import Path

from hydro_sdp.bags import STORAGES, write_bag
from hydro_sdp.cli.common import Outcome
from hydro_sdp.core.errors import ConfigurationError
from hydro_sdp.io.csv_logs import ANGLE_UNITS, CsvLog, read_csv_log

HELP = 'convert CSV logs (time, angle, command columns) into bags for identify'
DESCRIPTION = """\
Convert CSV logs of one joint into rosbag2 bags, one per file, named after it
(DIR/run1 for run1.csv), with /joint_states (radians) and /<joint>/valve_command:
the topics `identify`, `evaluate` and `diagnose` read.

Each row is one sample: the time in s, the measured angle, and the command the
logger applied at that time, in the valve's own units (volts, percent duty).
Choose columns by header name or by 0-based index; the first row is a header
when none of its cells is a number. Blank rows are skipped.

timing (docs/methods.md section 3.4):
  a row's command acts from that row's time until the next row, so the angle of
  the next row is the first that can show it; before the first row the command
  is taken to be the first row's, and the last row's command is not used.
  Only differences of the time column matter: it may start at any value and is
  shifted so the first row lands one sample period after t = 0, where a bag must
  start (the shift is reported). Irregular steps are kept as they are.

Refused with one line naming the file, row (as a spreadsheet numbers it, the
header being row 1) and column: a missing column, an empty or non-numeric cell,
NaN or infinite values, time that repeats or goes backwards, fewer than 2 rows.
All files are read and checked before any bag is written; each bag appears
whole or not at all.

examples:
  hydro-sdp import run1.csv run2.csv --out bags --joint arm \\
      --time t --angle arm_deg --command duty
  hydro-sdp import log.txt --out bags --joint boom --delimiter tab \\
      --time 0 --angle 3 --angle-unit rad --command 4 --command-negative 5
  hydro-sdp identify bags/run1 bags/run2 --out arm.yaml
"""


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the ``import`` command to the command line."""
    parser = subparsers.add_parser('import', help=HELP, description=DESCRIPTION,
                                   formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument('csvs', nargs='+', metavar='CSV', help='CSV log files, one run each')
    parser.add_argument('--out', required=True, metavar='DIR',
                        help='folder for the bags, one per CSV named after it '
                             '(a bag already there is replaced)')
    parser.add_argument('--joint', required=True, help='joint name written to JointState')
    parser.add_argument('--time', required=True, metavar='COL', help='time column, s')
    parser.add_argument('--angle', required=True, metavar='COL', help='angle column')
    parser.add_argument('--angle-unit', choices=ANGLE_UNITS, default='deg',
                        help='unit of the angle column (default: deg)')
    parser.add_argument('--command', required=True, metavar='COL',
                        help='valve command column, in the valve units')
    parser.add_argument('--command-negative', metavar='COL',
                        help='column subtracted from --command: the duty of the valve that '
                             'drives the other way, on machines that log one per direction')
    parser.add_argument('--delimiter', default=',', metavar='D',
                        help='cell delimiter: one character, or tab or space (default: ,)')
    parser.add_argument('--storage', choices=STORAGES, default='sqlite3',
                        help='rosbag2 storage (default: sqlite3)')
    parser.set_defaults(run=run)


def _targets(csvs: list[str], out: str) -> list[Path]:
    """One bag folder per CSV, refusing two CSVs that would write the same bag."""
    targets = [Path(out) / Path(csv).stem for csv in csvs]
    seen: dict[Path, str] = {}
    for csv, target in zip(csvs, targets):
        if target in seen:
            raise ConfigurationError(f'{seen[target]} and {csv} would both be written to '
                                     f'{target}; rename one')
        seen[target] = csv
    return targets


def run(args: argparse.Namespace) -> Outcome:
    """Run ``import``."""
    targets = _targets(args.csvs, args.out)
    logs: list[CsvLog] = [
        read_csv_log(csv, joint=args.joint, time=args.time, angle=args.angle,
                     command=args.command, command_negative=args.command_negative,
                     angle_unit=args.angle_unit, delimiter=args.delimiter)
        for csv in args.csvs]
    # Every file is checked above before the first bag is written.
    bags = [str(write_bag(target, [log.record], storage=args.storage))
            for target, log in zip(targets, logs)]
    samples = [len(log.record) for log in logs]
    payload = {'bags': bags, 'samples': samples, 'sources': list(args.csvs),
               'joint': args.joint, 'time_shift': [log.time_shift for log in logs]}
    lines = [f'wrote {bag} ({args.storage}): {count} samples of joint {args.joint} from {csv}, '
             f'{log.record.duration:.1f} s (time shifted by {log.time_shift:+.6g} s)'
             for bag, count, csv, log in zip(bags, samples, args.csvs, logs)]
    return Outcome(payload, lines)

"""``hydro-sdp import``: loggers' files (CSV, MDF4, MATLAB) as bags the other commands read."""

from __future__ import annotations

import argparse
from pathlib import Path

from hydro_sdp.bags import STORAGES, write_bag
from hydro_sdp.cli.common import add_text_options, Outcome
from hydro_sdp.core.errors import ConfigurationError
from hydro_sdp.io.logs import (
    ANGLE_UNITS, load_signals, MachineLog, MachineSpec, read_machine_log, single_joint_spec)

HELP = "convert loggers' files (CSV, MDF4, MATLAB) into bags for identify"
DESCRIPTION = """\
Convert loggers' files into rosbag2 bags, one per file, named after it
(DIR/run1 for run1.mf4), with /joint_states (radians) and /<joint>/valve_command:
the topics `identify`, `evaluate`, `diagnose` and `calibrate` read.

files, by their name:
  .mf4 .mdf  ASAM MDF4 (dSPACE ControlDesk, Vector CANape, ETAS INCA): channels by
             name, each on its channel group's own time base (--time optional: a
             channel whose values time its group's channels)
  .mat       MATLAB, v5 to v7 and v7.3 (HDF5): numeric vectors by name, struct
             fields as log.Boom_ang, all as long as the --time variable
  other      CSV: one row per sample, columns by name or 0-based index; lines
             of the logger's own above the header are skipped; the header block
             (names, then units or descriptions) is the rows above the first row
             of numbers (--header-row N names the names row). A dSPACE ControlDesk
             export (a row keyed trace_values) is read by its own layout: each
             section's time column (--time optional), signals by trace name or,
             for a block port (In1, Out1), by the last element of their path.
             Any common encoding: UTF-8, UTF-16 with a byte-order mark, a code
             page in the metadata (read byte by byte, --encoding to name it);
             delimiter , ; or tab found (a comma is the decimal point with ; or tab)

one joint: --joint NAME --angle COL --command COL [--command-negative COL]
a whole machine: --signals machine.yaml, for example

  time: t                    # column or variable (MDF4: the channels' time base)
  angle_unit: deg            # or rad
  joints:
    boom: {angle: Boom_ang, command: Boom_up_duty, command_negative: Boom_dn_duty}
    arm:  {angle: Arm_ang,  command: Arm_out_duty}
  signals:                   # more std_msgs/Float64 topics, e.g. for --load-topic
    boom/head_pressure: Boom_head_P

  writes /joint_states with every joint, /<joint>/valve_command per joint with a
  command (command - command_negative), and /<topic> per signal.

timing (docs/methods.md section 3.4):
  the first joint's angle samples are the bag's samples. A command logged at a
  time acts from then on, over the interval after it: a sample sees the last
  command logged strictly before it (on one row, the angle of the next row is
  the first that can show it); other angles and signals are the last value
  logged at or before the sample; before a channel's first value, that value is
  held. Channels at other rates are put on the samples the same way. Only
  differences of time matter: the first sample lands one sample period after
  t = 0 (the shift is reported).

Refused with one line naming the file, the channel (or row and column) and the
reason: a missing channel, column or variable, a cell or value that is not a
finite number, time that repeats or goes backwards, fewer than 2 samples, a
joint without an angle, a signals file with an unknown key. All files are read
and checked before any bag is written; each bag appears whole or not at all.

examples:
  hydro-sdp import run1.csv run2.csv --out bags --joint arm \\
      --time t --angle arm_deg --command duty
  hydro-sdp import log.txt --out bags --joint boom --delimiter tab --header-row 4 \\
      --time 0 --angle 3 --angle-unit rad --command 4 --command-negative 5
  hydro-sdp import day1/*.mf4 --out bags --signals machine.yaml
  hydro-sdp import arm_*.csv --out bags --joint arm --angle Arm_ang \
      --command Arm_duty              # ControlDesk exports: no --time needed
  hydro-sdp diagnose bags/* --joint arm --model arm.yaml --load-topic /boom/head_pressure
"""


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the ``import`` command to the command line."""
    parser = subparsers.add_parser('import', help=HELP, description=DESCRIPTION,
                                   formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument('files', nargs='+', metavar='FILE',
                        help="loggers' files, one run each: .csv (or any text), .mf4, .mat")
    parser.add_argument('--out', required=True, metavar='DIR',
                        help='folder for the bags, one per file named after it '
                             '(a bag already there is replaced)')
    parser.add_argument('--signals', metavar='YAML',
                        help="the machine's joints and signals (instead of --joint, --angle, "
                             '--command)')
    parser.add_argument('--joint', help='joint name written to JointState')
    parser.add_argument('--time', metavar='COL',
                        help="time column or variable, s (MDF4: default each channel's own "
                             "time base; with --signals it replaces the file's time)")
    parser.add_argument('--angle', metavar='COL', help='angle column, channel or variable')
    parser.add_argument('--angle-unit', choices=ANGLE_UNITS, default='deg',
                        help='unit of the angle (default: deg)')
    parser.add_argument('--command', metavar='COL',
                        help='valve command, in the valve units')
    parser.add_argument('--command-negative', metavar='COL',
                        help='subtracted from --command: the duty of the valve that drives the '
                             'other way, on machines that log one per direction')
    add_text_options(parser)
    parser.add_argument('--storage', choices=STORAGES, default='sqlite3',
                        help='rosbag2 storage (default: sqlite3)')
    parser.set_defaults(run=run)


def machine_spec(args: argparse.Namespace) -> MachineSpec:
    """Return the joints and signals the command line names (``--signals`` or one joint)."""
    names = ('joint', 'angle', 'command', 'command_negative')
    single = [f'--{name.replace("_", "-")}' for name in names if getattr(args, name)]
    if args.signals:
        if single:
            raise ConfigurationError(f"{', '.join(single)}: the signals file {args.signals} "
                                     'names the joints; give one or the other')
        spec = load_signals(args.signals)
        if args.time:
            spec = MachineSpec(spec.joints, spec.signals, args.time, spec.source)
        return spec
    missing = [f'--{name}' for name in ('joint', 'angle', 'command') if not getattr(args, name)]
    if missing:
        raise ConfigurationError(f"give --signals FILE, or {', '.join(missing)} for one joint")
    return single_joint_spec(args.joint, args.angle, args.command, time=args.time,
                             command_negative=args.command_negative,
                             angle_unit=args.angle_unit)


def _targets(files: list[str], out: str) -> list[Path]:
    """One bag folder per file, refusing two files that would write the same bag."""
    targets = [Path(out) / Path(name).stem for name in files]
    seen: dict[Path, str] = {}
    for name, target in zip(files, targets):
        if target in seen:
            raise ConfigurationError(f'{seen[target]} and {name} would both be written to '
                                     f'{target}; rename one')
        seen[target] = name
    return targets


def write_machine_bag(target: Path, log: MachineLog, storage: str) -> Path:
    """Write one file's records and signals as a bag (commands stamped as the timing rule says)."""
    names = [record.joint for record in log.records]
    return write_bag(target, log.records, storage=storage, signals=log.signals,
                     without_command=[name for name in names if name not in log.commanded])


def run(args: argparse.Namespace) -> Outcome:
    """Run ``import``."""
    spec = machine_spec(args)
    targets = _targets(args.files, args.out)
    logs = [read_machine_log(name, spec, header_row=args.header_row, delimiter=args.delimiter,
                             encoding=args.encoding)
            for name in args.files]
    # Every file is checked above before the first bag is written.
    bags = [str(write_machine_bag(target, log, args.storage))
            for target, log in zip(targets, logs)]
    joints = list(spec.joints)
    payload = {'bags': bags, 'samples': [log.samples for log in logs], 'joints': joints,
               'signals': list(spec.signals), 'sources': list(args.files),
               'time_shift': [log.time_shift for log in logs],
               'notes': [list(log.notes) for log in logs]}
    if len(joints) == 1:
        payload['joint'] = joints[0]
    what = f'joint {joints[0]}' if len(joints) == 1 else f"joints {', '.join(joints)}"
    if spec.signals:
        what += f" and signals {', '.join(spec.signals)}"
    lines = [f'wrote {bag} ({args.storage}): {log.samples} samples of {what} from {name}, '
             f'{log.records[0].duration:.1f} s (time shifted by {log.time_shift:+.6g} s)'
             for bag, log, name in zip(bags, logs, args.files)]
    lines += [f'{name}: {note}' for log, name in zip(logs, args.files) for note in log.notes]
    return Outcome(payload, lines)

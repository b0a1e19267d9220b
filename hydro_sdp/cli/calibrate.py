"""``hydro-sdp calibrate``: from a machine's recordings to a checked controller and a report."""

from __future__ import annotations

import argparse
from dataclasses import replace
import math
from pathlib import Path
from typing import TYPE_CHECKING

from hydro_sdp.bags import STORAGE_SUFFIXES
from hydro_sdp.cli.common import (
    add_bag_options, add_text_options, finite_float, json_number, Outcome, Payload,
    period_seconds, read_bag_records, table)
from hydro_sdp.cli.design import complex_pole
from hydro_sdp.cli.progress import ProgressBar
from hydro_sdp.core.errors import ConfigurationError
from hydro_sdp.core.model.records import Record
from hydro_sdp.core.model.timing import SamplePeriod
from hydro_sdp.io.atomic import atomic_directory, atomic_write_text
from hydro_sdp.io.controller_files import save_controller
from hydro_sdp.io.logs import ANGLE_UNITS, read_machine_log, single_joint_spec
from hydro_sdp.io.model_files import save_model
import yaml

if TYPE_CHECKING:
    from hydro_sdp.core.calibration import CalibrationResult
    from hydro_sdp.core.control.loop_chatter import Chatter
    from hydro_sdp.ros.parameters.spec import ParameterValue

    #: A ROS 2 parameter file: node pattern, ``ros__parameters``, name and value.
    ParameterFile = dict[str, dict[str, dict[str, ParameterValue]]]

HELP = 'identify, diagnose, design and check a joint in one go, with a report'
DESCRIPTION = """\
From a machine's recordings to a working controller, in one command:

  1. identify the joint (map family chosen on held-out experiments);
  2. evaluate it on the --validation recordings, or, without them, on whole
     input recordings held out (every third one; the second of two); with one
     recording the error is in-sample, and a warning says so;
  3. diagnose what the model misses and add the named effects (valve lag, angle
     factor...);
  4. design the PIP-IDZ controller from that final model, on the integrator
     with its delay and valve lag; the IDZ inverts chords of an sdp map (the
     paper's IDZ) and the map itself, as a table, for pwl, poly and power_sat;
  5. check it in closed loop on the final model, effects included, reading the
     angle with the noise found in the records: steps from 20 % of the stroke
     to 50 %, 80 %, 50 %, 20 % and a ramp. Every step must settle into +-0.5
     deg within 6 s plus its travel at a quarter of full speed, overshoot at
     most 10 %, and no hold may end in a limit cycle. If the chords fail, the
     table takes their place; if the check still fails, the dominant poles
     move toward 1 and the controller is designed again (up to 4 times), and
     the warnings say so. If no design passes, the last one is written, the
     check reads FAILED, the warnings give every failure and what stands in
     the way: the check is run again with the map, the delay, the valve lag,
     the noise and the other effects each idealised in turn.

Written to --out DIR, all at once (built beside it and renamed when complete;
an existing non-empty DIR is refused unless --force, and replaced only at the
end): model.yaml, controller.yaml, params.yaml (a ROS 2 parameter file for
pip_controller, hydro_plant and sdp_identifier with these files' absolute
paths; only values that differ from the nodes' defaults) and report/
(summary.md, velocity map with the level speeds, evaluation, closed-loop
check, and diagnosis/ with the residual signature and the gap).

Inputs are bags or loggers' files: a plain file that is not a .db3 or .mcap
storage file is read as a logger's file, CSV, MDF4 (.mf4) or MATLAB (.mat), as
`hydro-sdp import` reads it (one row per sample; the command on a row acts until
the next row; see `hydro-sdp import --help`), and needs --joint, --time,
--angle and --command (column names or 0-based indices; --time is optional
for MDF4, whose channels carry their own time, and for a dSPACE ControlDesk
CSV export, whose sections name theirs).

The controller runs every whole number of the records' samples: the control
period is the whole multiple of their sample period nearest --control-period,
and is reported (records 0.0099909 s apart get 5 samples, 0.0499545 s).

model.yaml remembers the command topic of the bags (key command_topic), so
evaluate and diagnose read the same topic without --command-topic.

Labels give the command in the model's own unit: % for input limits [0, 100]
or [-100, 100], V for [-10, 10] or [0, 10], otherwise --command-unit.

examples:
  hydro-sdp calibrate steps_bag random_1 --validation random_2 --out j2_calibrated
  hydro-sdp calibrate run1.csv run2.csv run3.csv --joint arm --time t \\
      --angle arm_deg --command duty --input-limits -100 100 --out arm
  ros2 run hydro_sdp controller_node --ros-args --params-file arm/params.yaml
"""


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the ``calibrate`` command to the command line."""
    parser = subparsers.add_parser('calibrate', help=HELP, description=DESCRIPTION,
                                   formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument('inputs', nargs='+', metavar='BAG_OR_CSV',
                        help='recordings of one joint: bags or CSV logs')
    parser.add_argument('--validation', nargs='+', metavar='BAG_OR_CSV', default=[],
                        help='held-out recordings for the MAE (default: whole input '
                             'recordings held out)')
    add_bag_options(parser)
    parser.add_argument('--load-topic', metavar='TOPIC',
                        help='Float64 topic of a measured load (a cylinder pressure) in the bags, '
                             'for load_dependence; remembered in model.yaml')
    parser.add_argument('--rest', type=finite_float, metavar='V',
                        help='command that holds the joint still (default: found by identify)')
    parser.add_argument('--input-limits', nargs=2, type=finite_float, metavar=('LOW', 'HIGH'),
                        help='command range of the valve, written to the model')
    parser.add_argument('--angle-limits', nargs=2, type=finite_float, metavar=('LOW', 'HIGH'),
                        help='known end stops, deg (default: those seen in the data)')
    parser.add_argument('--control-period', type=period_seconds, default=SamplePeriod(0.05),
                        help='control period, s (default: 0.05); the controller runs at the '
                             "nearest whole multiple of the records' sample period")
    parser.add_argument('--poles', nargs='+', type=complex_pole, metavar='P',
                        help='closed-loop poles to start from, the dominant ones first; '
                             'a valve lag keeps its own pole and the rest are 0 (default: '
                             'LQ design)')
    parser.add_argument('--iterations', type=int, default=4,
                        help='most effects the diagnosis adds (default: 4)')
    parser.add_argument('--command-unit',
                        help='unit of the command in labels (default: from the input limits)')
    parser.add_argument('--out', required=True, metavar='DIR', help='folder to write')
    parser.add_argument('--force', action='store_true',
                        help='replace DIR if it exists and is not empty')
    logs = parser.add_argument_group("loggers' files (CSV, MDF4, MATLAB)")
    logs.add_argument('--time', metavar='COL',
                      help="time column or variable, s (MDF4: default the channels' own)")
    logs.add_argument('--angle', metavar='COL', help='angle column, channel or variable')
    logs.add_argument('--angle-unit', choices=ANGLE_UNITS, default='deg',
                      help='unit of the angle (default: deg)')
    logs.add_argument('--command', metavar='COL', help='command column, channel or variable')
    logs.add_argument('--command-negative', metavar='COL',
                      help='subtracted from --command (one valve per direction)')
    add_text_options(logs)
    parser.set_defaults(run=run)


def is_log(path: str) -> bool:
    """Whether an input is read as a logger's file: a plain file that is no bag storage file."""
    source = Path(path)
    return (source.is_file() and source.suffix not in STORAGE_SUFFIXES
            and source.name != 'metadata.yaml')


def read_inputs(paths: list[str], args: argparse.Namespace, label: str,
                preferred_topic: str | None = None) -> tuple[list[Record], str | None]:
    """
    Read bags and CSV logs as records of one joint, with a progress bar.

    ``label``: progress bar label.
    ``preferred_topic``: command topic used without ``--command-topic`` where a bag has it.
    Returns: ``(records, topic)``: the command topic every bag was read from, or ``None`` when
    there are no bags or they used different topics.
    """
    records = []
    topics: set[str] = set()
    with ProgressBar(label, len(paths)) as bar:
        for done, path in enumerate(paths, start=1):
            if is_log(path):
                # A CSV or MATLAB file without --time says so itself (a ControlDesk export
                # names its own time, as MDF4 channels carry theirs).
                missing = [f'--{name}' for name in ('joint', 'angle', 'command')
                           if not getattr(args, name)]
                if missing:
                    raise ConfigurationError(f"{path} is read as a logger's file and needs "
                                             f'{", ".join(missing)}')
                spec = single_joint_spec(args.joint, args.angle, args.command, time=args.time,
                                         command_negative=args.command_negative,
                                         angle_unit=args.angle_unit)
                records.append(read_machine_log(path, spec, header_row=args.header_row,
                                                delimiter=args.delimiter,
                                                encoding=args.encoding).records[0])
            else:
                # The reader of identify, evaluate and diagnose: cut at gaps, with the load
                # and the other joints (so the diagnosis can name flow_sharing).
                pieces, topic = read_bag_records(
                    path, args.joint, args.command_topic, preferred_topic=preferred_topic,
                    load_topic=args.load_topic, others=True)
                records.extend(pieces)
                topics.add(topic)
            bar.update(done)
    return records, (topics.pop() if len(topics) == 1 else None)


def check_out(out: Path, force: bool) -> None:
    """Refuse an existing non-empty output folder unless ``force``."""
    if out.exists() and not out.is_dir():
        raise ConfigurationError(f'{out} exists and is not a folder')
    if out.is_dir() and any(out.iterdir()) and not force:
        raise ConfigurationError(f'{out} exists and is not empty; use --force to replace it')


def ros_parameters(result: CalibrationResult, folder: Path) -> ParameterFile:
    """Return the ROS 2 parameter file for this joint's nodes."""
    model_file = str(folder / 'model.yaml')
    dt = result.identification.sample_period
    plant: dict[str, ParameterValue] = {'model_file': model_file}
    identifier: dict[str, ParameterValue] = {'model_file': model_file}
    if not math.isclose(dt, 0.01):
        plant['sample_period'] = identifier['sample_period'] = float(dt)
    noise = result.identification.segmentation.noise_std
    if math.isfinite(noise) and noise > 1e-6 and not math.isclose(noise, 0.03, rel_tol=0.05):
        identifier['noise_std'] = float(f'{noise:.3g}')
    if not math.isclose(result.spec.control_period, 0.05):
        identifier['control_period'] = float(result.spec.control_period)
    parameters: ParameterFile = {
        '/**/pip_controller': {'ros__parameters': {
            'model_file': model_file, 'controller_file': str(folder / 'controller.yaml')}},
        '/**/hydro_plant': {'ros__parameters': plant}}
    parameters['/**/sdp_identifier'] = {'ros__parameters': identifier}
    return parameters


def chatter_keys(chatter: Chatter) -> Payload:
    """Return the ``--json`` keys of the valve's work at hold (methods.md section 5.7)."""
    from hydro_sdp.core.control.loop_chatter import MAX_PULSE_RATE
    return {'pulse_rate': chatter.pulse_rate, 'pulse_bound': MAX_PULSE_RATE,
            'travel_rate': chatter.travel_rate, 'travel_share': chatter.travel_share,
            'travel_bound': chatter.travel_bound, 'held': chatter.duration,
            'edges': None if chatter.edges is None else list(chatter.edges)}


def describe(result: CalibrationResult, folder: Path) -> Payload:
    """Return the ``--json`` object of a calibration written to ``folder``."""
    check = result.check
    warnings = list(result.warnings)
    return {
        'model': str(folder / 'model.yaml'),
        'controller': str(folder / 'controller.yaml'),
        'params': str(folder / 'params.yaml'),
        'report': str(folder / 'report'),
        'joint': result.model.joint,
        'kind': result.model.kind,
        'rest': result.identification.segmentation.rest,
        'effect': result.effect,
        'effects': list(result.effects),
        'sample_period': result.identification.sample_period,
        'control_period': result.spec.control_period,
        'control_samples': None if result.control is None else result.control.samples,
        'mae': {'identified': json_number(result.mae_identified),
                'final': json_number(result.mae_final), 'validation': result.validation_note},
        'closed_loop': {
            'passed': check.passed,
            'step_size': [m.size for m in check.steps],
            'settling_time': [json_number(m.settling_time) for m in check.steps],
            'overshoot': [m.overshoot for m in check.steps],
            'ramp_error': check.ramp_error,
            'ramp_settling': json_number(check.ramp_settling),
            'limit_cycles': check.cycles,
            'chatter': chatter_keys(check.chatter),
            'designs': [list(poles) for poles in result.designs],
            'idz_forms': list(result.forms),
            'idz_fades': list(result.fades),
            'trade': [{'fade': f.fade, 'passed': f.passed,
                       'settling_time': [json_number(x) for x in f.settling],
                       'overshoot': f.overshoot, 'pulse_rate': f.pulse_rate,
                       'travel_rate': f.travel_rate, 'travel_share': f.travel_share}
                      for f in result.trade],
            'in_the_way': list(result.in_the_way),
            'idealised': {o.element: {'passed': o.passed, 'failures': o.failures}
                          for o in result.obstacles}},
        'plausible': None if result.plausible is None else result.plausible.to_mapping(),
        'warnings': warnings,
    }


def plausible_lines(result: CalibrationResult) -> list[str]:
    """Return the worst figures of the check over the models the data do not rule out."""
    if result.plausible is None or not result.plausible.checks:
        return []
    plausible = result.plausible
    worst = plausible.worst()
    units = {'settling_time': ('settling', 's'), 'overshoot': ('overshoot', '%'),
             'steady_error': ('steady error', 'deg'), 'pulse_rate': ('pulses at hold', '/s')}
    lines = [f'check over {len(plausible.checks)} models the data do not rule out: '
             f'{len(plausible.checks) - len(plausible.failed)} pass; worst:']
    lines += [f'  {label} {value:.3g} {unit} ({name})' for metric, (label, unit) in units.items()
              for value, name in [worst[metric]]]
    return lines


def control_line(result: CalibrationResult) -> str:
    """Return the line naming the control period as whole samples of the records' period."""
    dt, period = result.identification.sample_period, result.spec.control_period
    control = result.control
    samples = control.samples if control is not None else round(period / dt)
    asked = '' if control is None or control.asked == period else \
        f" (the whole multiple of the records' period nearest the {control.asked:g} s asked)"
    return f'control every {samples} samples of {dt:.9g} s: {period:.9g} s{asked}'


class _StageBars:
    """One progress bar per stage of the calibration."""

    def __init__(self) -> None:
        self.stage = ''
        self.bar: ProgressBar | None = None

    def __call__(self, stage: str, done: float, total: float) -> None:
        if stage != self.stage:
            self.close()
            self.stage, self.bar = stage, ProgressBar(f'calibrate: {stage}', total)
        if self.bar is not None:
            self.bar.update(done)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()
            self.bar = None


def run(args: argparse.Namespace) -> Outcome:
    """Run ``calibrate``."""
    from hydro_sdp.core.calibration import calibrate, CalibrationSettings
    from hydro_sdp.plots import command_unit_of
    from hydro_sdp.report.calibration import write_report

    out = Path(args.out).resolve()
    check_out(out, args.force)
    if args.iterations < 0:
        raise ConfigurationError(f'--iterations must be >= 0, got {args.iterations}')
    records, topic = read_inputs(args.inputs, args, 'reading recordings')
    # Validation bags are read from the command topic the inputs were read from.
    validation = read_inputs(args.validation, args, 'reading validation recordings',
                             preferred_topic=topic)[0] if args.validation else []
    settings = CalibrationSettings(
        rest=args.rest, input_limits=tuple(args.input_limits) if args.input_limits else None,
        angle_limits=tuple(args.angle_limits) if args.angle_limits else None,
        control_period=args.control_period,
        poles=tuple(args.poles) if args.poles else None, iterations=args.iterations)
    bars = _StageBars()
    try:
        result = calibrate(records, validation or None, settings, on_stage=bars)
    finally:
        bars.close()
    unit = command_unit_of(result.model, args.command_unit)
    with atomic_directory(out) as building:
        building.mkdir()
        loaded = args.load_topic if result.model.effect('load_dependence') is not None else None
        save_model(replace(result.model, command_topic=topic, load_topic=loaded),
                   building / 'model.yaml')
        save_controller(result.spec, building / 'controller.yaml')
        atomic_write_text(building / 'params.yaml', yaml.safe_dump(
            ros_parameters(result, out), sort_keys=False, default_flow_style=False))
        write_report(building / 'report', result, unit)
    payload = describe(result, out)
    rows = [[f'{m.size:+.2f}', 'never' if not math.isfinite(m.settling_time)
             else f'{m.settling_time:.2f}', f'{m.overshoot:.1f}']
            for m in result.check.steps]
    lines = [f'joint {result.model.joint}: {result.model.kind} model, named effect '
             f'{result.effect}; validation MAE {result.mae_identified:.4g} -> '
             f'{result.mae_final:.4g} deg ({result.validation_note})',
             f'closed-loop check on the final model: '
             f'{"passed" if result.check.passed else "FAILED"}']
    lines += table(rows, ['step (deg)', 'settling (s)', 'overshoot (%)'])
    lines.append(f'IDZ: {result.forms[-1] if result.forms else "chord"}; design plant: '
                 f'{result.spec.delay_samples} samples of delay'
                 + ('' if result.spec.valve_lag is None
                    else f', valve lag {result.spec.valve_lag:.3g} s')
                 + ('' if result.spec.oscillation is None
                    else f', link mode {result.spec.oscillation[0]:.3g} Hz'))
    lines.append(control_line(result))
    lines += plausible_lines(result)
    lines += [f'warning: {w}' for w in payload['warnings']]
    lines += [f'wrote {payload[key]}' for key in ('model', 'controller', 'params')]
    lines.append(f'report: {out / "report" / "summary.md"}')
    return Outcome(payload, lines)

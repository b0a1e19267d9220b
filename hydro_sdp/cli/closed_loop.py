"""``hydro-sdp closed-loop``: offline PIP-IDZ closed loop, recorded as a bag."""

from __future__ import annotations

import argparse
import math
import sys

from hydro_sdp.bags import STORAGES, write_bag
from hydro_sdp.cli.common import (
    finite_float, non_negative_float, Outcome, period_seconds, positive_float, table)
from hydro_sdp.cli.progress import ProgressBar
from hydro_sdp.cli.trajectory_loop import add_trajectory_options, run_trajectory
from hydro_sdp.core.control.loop_simulation import (
    LoopJoint, run_closed_loop, step_metrics, step_setpoints)
from hydro_sdp.core.control.safety import clamp_setpoint, SETPOINT_MARGIN
from hydro_sdp.core.errors import ConfigurationError
from hydro_sdp.core.model.records import Record
from hydro_sdp.core.model.sample_period import control_period_on
from hydro_sdp.core.model.timing import SamplePeriod
from hydro_sdp.io.controller_files import controller_for
from hydro_sdp.io.model_files import load_model
import numpy as np

HELP = 'simulate the PIP-IDZ closed loop offline and record it as a bag'
DESCRIPTION = """\
Simulate a joint model under PIP-IDZ control: the plant at its sample period,
the controller at its own (a whole multiple), the command held in between, the
model's effects included. Each set-point is held for --hold seconds; one beyond
the end stops is clamped to --setpoint-margin inside them (with a warning), as
the controller node does. The bag gets
/joint_states, /<joint>/valve_command and /<joint>/setpoint; the report gives the
settling time (into +-band), overshoot and steady error of every step.

With --trajectory FILE instead of --setpoints, one model per joint follows a
trajectory from --start-at seconds on, interpolated as ROS's
JointTrajectoryController does: a YAML file (format: hydro_sdp/trajectory/v1)
with joint_names and points ({time_from_start: s, positions: [deg, ...],
velocities: [deg/s, ...] optional}), or with kinematics: FILE and line:
{start: [x, z], end: [x, z], speed: m/s or duration: s} for a straight line
of the bucket tip; or a CSV with the header time,<joint>,... (s, deg). Joints
start at its first point. The set-point rate is fed forward through the IDZ
(--no-feedforward: the PIP alone). The report gives the RMS tracking error
during the motion and the final error per joint, and for a line the distance
of the tip from it (path_error_mm); --plot draws the tip path and that distance.

examples:
  hydro-sdp closed-loop config/brokk_j2.yaml --setpoints 20 -10 50 --hold 10 \\
      --out loop_bag --plot loop.png
  hydro-sdp closed-loop config/lucie_boom.yaml config/lucie_dipper.yaml \\
      --trajectory config/lucie_line.yaml --out line_bag --plot line.png
"""


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the ``closed-loop`` command to the command line."""
    parser = subparsers.add_parser('closed-loop', help=HELP, description=DESCRIPTION,
                                   formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument('model', nargs='+',
                        help='model file of the simulated joint (one per joint with '
                             '--trajectory)')
    parser.add_argument('--controller', nargs='+',
                        help='controller file from `design`, one per model (default: designed '
                             'from the model)')
    parser.add_argument('--setpoints', nargs='+', type=finite_float,
                        metavar='DEG', help='set-points in degrees, each held --hold seconds')
    add_trajectory_options(parser)
    parser.add_argument('--hold', type=positive_float, default=10.0,
                        help='time each set-point is held, s (default: 10)')
    parser.add_argument('--out', required=True, help='bag folder to write')
    parser.add_argument('--sample-period', type=period_seconds, default=SamplePeriod(0.01),
                        help='plant sample period, s (default: 0.01)')
    parser.add_argument('--control-period', type=period_seconds, default=SamplePeriod(0.05),
                        help='control period when designing from the model, s (default: 0.05; '
                             'the nearest whole multiple of --sample-period)')
    parser.add_argument('--y0', type=finite_float,
                        help='starting angle, deg (default: 0, or mid-travel if 0 is outside '
                             'the end stops)')
    parser.add_argument('--noise', type=non_negative_float, default=0.0,
                        help='std of the angle measurement noise, deg (default: 0)')
    parser.add_argument('--seed', type=int, default=0, help='noise seed (default: 0)')
    parser.add_argument('--setpoint-margin', type=non_negative_float, default=SETPOINT_MARGIN,
                        help='set-points are kept this far inside the end stops, deg '
                             f'(default: {SETPOINT_MARGIN:g})')
    parser.add_argument('--band', type=positive_float, default=0.5,
                        help='settling band, deg (default: 0.5)')
    parser.add_argument('--storage', choices=STORAGES, default='sqlite3',
                        help='rosbag2 storage (default: sqlite3)')
    parser.add_argument('--plot', help="PNG of angle, u and v (the paper's Fig. 7)")
    parser.set_defaults(run=run)


def _finite_or_none(value: float) -> float | None:
    return value if math.isfinite(value) else None


def run(args: argparse.Namespace) -> Outcome:
    """Run ``closed-loop``."""
    if (args.setpoints is None) == (args.trajectory is None):
        raise ConfigurationError('give --setpoints or --trajectory, one of them')
    if args.trajectory is not None:
        return run_trajectory(args)
    if len(args.model) != 1 or (args.controller and len(args.controller) != 1):
        raise ConfigurationError('--setpoints drives one joint: give one model (and at most '
                                 'one controller)')
    model = load_model(args.model[0])
    spec = controller_for(model, args.controller[0] if args.controller else None,
                          control_period_on(args.control_period, args.sample_period).seconds)
    y0 = args.y0
    if y0 is None:
        limits = model.angle_limits
        y0 = 0.0 if limits is None or limits[0] < 0.0 < limits[1] else 0.5 * sum(limits)
    levels = []
    for level in args.setpoints:
        safe = clamp_setpoint(level, model.angle_limits, args.setpoint_margin)
        if safe != level:
            sys.stderr.write(f'warning: set-point {level:g} deg is beyond the end stops '
                             f'{list(model.angle_limits or ())} less the margin '
                             f'{args.setpoint_margin:g} deg; using {safe:g} deg\n')
        levels.append(safe)
    setpoint = step_setpoints(levels, args.hold, args.sample_period)
    with ProgressBar('closed loop', setpoint.size) as bar:
        trace = run_closed_loop(
            [LoopJoint(model, spec.controller(), setpoint, y0)], dt=args.sample_period,
            control_period=spec.control_period, noise_std=args.noise, seed=args.seed,
            on_sample=lambda done, total: bar.update(done))[0]
    metrics = step_metrics(trace, band=args.band, initial=y0)
    # Time starts one period in so that the first command has a time to be sent at.
    record = Record(trace.t + args.sample_period, trace.v, trace.measured, joint=model.joint)
    bag = write_bag(args.out, [record], storage=args.storage,
                    setpoints={model.joint: trace.setpoint})
    steps = [{'start': m.start, 'size': m.size, 'settling_time': _finite_or_none(m.settling_time),
              'overshoot': m.overshoot, 'steady_error': m.steady_error} for m in metrics]
    worst_settling = max((m.settling_time for m in metrics), default=0.0)
    payload = {
        'bag': str(bag), 'samples': len(record), 'joint': model.joint,
        'settling_time': _finite_or_none(worst_settling),
        'overshoot': max((m.overshoot for m in metrics), default=0.0),
        'steady_error': max((abs(m.steady_error) for m in metrics), default=0.0),
        'band': args.band, 'steps': steps,
    }
    if args.plot:
        from hydro_sdp.plots import plot_closed_loop, save_figure

        payload['plot'] = str(save_figure(
            plot_closed_loop([trace], title=f'PIP-IDZ control of joint {model.joint}'),
            args.plot))
    rows = [[f'{m.start:.1f}', f'{m.size:+.2f}',
             'never' if not math.isfinite(m.settling_time) else f'{m.settling_time:.2f}',
             f'{m.overshoot:.2f}', f'{m.steady_error:+.3f}'] for m in metrics]
    lines = [f'closed loop of joint {model.joint}: {len(record)} samples, '
             f'control every {spec.control_period:g} s; settling into +-{args.band:g} deg']
    lines += table(rows, ['step at (s)', 'size (deg)', 'settling (s)', 'overshoot (%)',
                          'steady error (deg)'])
    lines.append(f'wrote {bag}')
    if args.plot:
        lines.append(f'wrote {payload["plot"]}')
    if np.isnan(trace.y).any():  # pragma: no cover - the simulation never produces NaN
        raise ConfigurationError('the closed loop produced NaN angles')
    return Outcome(payload, lines)

"""``hydro-sdp closed-loop --trajectory``: several joints following a trajectory offline."""

from __future__ import annotations

import argparse
from dataclasses import dataclass

from hydro_sdp.bags import write_bag
from hydro_sdp.cli.common import non_negative_float, Outcome, table
from hydro_sdp.cli.progress import ProgressBar
from hydro_sdp.core.arrays import FloatArray
from hydro_sdp.core.control.controller_spec import ControllerSpec
from hydro_sdp.core.control.kinematics import distance_to_segment
from hydro_sdp.core.control.loop_simulation import LoopJoint, LoopTrace, run_closed_loop
from hydro_sdp.core.control.trajectory import check_trajectory, TrajectorySampler
from hydro_sdp.core.errors import ConfigurationError
from hydro_sdp.core.model.joint_model import JointModel
from hydro_sdp.core.model.records import Record
from hydro_sdp.core.model.sample_period import control_period_on
from hydro_sdp.core.model.timing import SamplePeriod
from hydro_sdp.io.controller_files import controller_for
from hydro_sdp.io.model_files import load_model
from hydro_sdp.io.trajectory_files import load_trajectory, TrajectoryFile
import numpy as np


def add_trajectory_options(parser: argparse.ArgumentParser) -> None:
    """Add the trajectory options of ``closed-loop``."""
    parser.add_argument('--trajectory', metavar='FILE',
                        help='follow a trajectory file (YAML or CSV of time and joint angles, or '
                             'a YAML tip line) instead of --setpoints')
    parser.add_argument('--kinematics', metavar='FILE',
                        help='kinematics file for a line (default: the one the file names)')
    parser.add_argument('--feedforward', action=argparse.BooleanOptionalAction, default=True,
                        help='feed the set-point rate forward through the IDZ (default: on)')
    parser.add_argument('--start-at', type=non_negative_float, default=1.0,
                        help='time the trajectory starts, s (default: 1)')
    parser.add_argument('--settle', type=non_negative_float, default=5.0,
                        help='time simulated after its last point, s (default: 5)')


@dataclass(frozen=True, eq=False)
class TrajectoryRun:
    """
    A trajectory run and its figures.

    Parameters
    ----------
    traces : list of LoopTrace
        One per joint.
    motion : tuple[float, float]
        Start and end of the motion, s.
    rms_error, final_error : dict of str to float
        RMS of ``y - d`` during the motion and ``y - d`` at the end, per joint, degrees.
    path_error_mm : FloatArray or None
        Distance of the tip from the line at every sample, mm (line files only).
    tip : tuple of FloatArray or None
        Tip position ``(x, z)`` at every sample, m (line files only).

    """

    traces: list[LoopTrace]
    motion: tuple[float, float]
    rms_error: dict[str, float]
    final_error: dict[str, float]
    path_error_mm: FloatArray | None
    tip: tuple[FloatArray, FloatArray] | None = None

    def path_in_motion(self) -> tuple[float, float] | None:
        """Return the largest and the RMS distance from the line during the motion, mm."""
        if self.path_error_mm is None:
            return None
        t = self.traces[0].t
        path = self.path_error_mm[(t >= self.motion[0]) & (t <= self.motion[1])]
        return float(np.max(path)), float(np.sqrt(np.mean(path ** 2)))

    def path_after_motion(self) -> float | None:
        """Return the largest distance from the line after the motion ended, mm (None: none)."""
        if self.path_error_mm is None:
            return None
        after = self.path_error_mm[self.traces[0].t > self.motion[1]]
        return float(np.max(after)) if after.size else None

    def error_table(self) -> list[str]:
        """Return the per-joint table of the RMS error in motion and the final error."""
        rows = [[trace.joint, f'{self.rms_error[trace.joint]:.3f}',
                 f'{self.final_error[trace.joint]:+.3f}'] for trace in self.traces]
        return table(rows, ['joint', 'RMS error in motion (deg)', 'final error (deg)'])


def simulate_trajectory(models: list[JointModel], specs: list[ControllerSpec],
                        plan: TrajectoryFile, *, dt: SamplePeriod, start_at: float, settle: float,
                        feedforward: bool = True, noise_std: float = 0.0, seed: int = 0,
                        margin: float = 0.5, bar: ProgressBar | None = None) -> TrajectoryRun:
    """
    Run the joints through the trajectory and measure how well they follow it.

    ``models``, ``specs``: joint models and their controllers, same order, one control period.
    ``dt``: plant sample period, s.
    ``start_at``, ``settle``: start of the trajectory and time simulated after its end, s.
    ``noise_std``: angle measurement noise, degrees.
    ``margin``: set-point margin inside the end stops, degrees.
    """
    check_trajectory(plan.trajectory, {m.joint: m.angle_limits for m in models}, margin)
    periods = {spec.control_period for spec in specs}
    if len(periods) != 1:
        raise ConfigurationError(f'all controllers must share one control period, got '
                                 f'{sorted(periods)} s')
    trajectory = plan.trajectory
    initial = {}
    for model in models:
        if model.joint in trajectory.joint_names:
            initial[model.joint] = float(
                trajectory.positions[0, trajectory.joint_names.index(model.joint)])
        else:
            limits = model.angle_limits
            initial[model.joint] = (0.0 if limits is None or limits[0] < 0.0 < limits[1]
                                    else 0.5 * sum(limits))
    sampler = TrajectorySampler(initial)
    sampler.replace(trajectory, start_at)
    end = start_at + trajectory.duration
    samples = int(round((end + settle) / dt)) + 1
    t = np.arange(samples) * dt
    loop = []
    for model, spec in zip(models, specs):
        setpoint = sampler.setpoints(model.joint, t)
        ahead = None
        if feedforward:
            ahead = np.array([sampler.feedforward(model.joint, float(time), spec.control_period,
                                                  spec.delay_samples) for time in t])
        loop.append(LoopJoint(model, spec.controller(), setpoint, initial[model.joint], ahead))
    traces = run_closed_loop(
        loop, dt=dt, control_period=specs[0].control_period, noise_std=noise_std, seed=seed,
        on_sample=None if bar is None else (lambda done, total: bar.update(done)))
    moving = (t >= start_at) & (t <= end)
    rms = {trace.joint: float(np.sqrt(np.mean((trace.y - trace.setpoint)[moving] ** 2)))
           for trace in traces}
    final = {trace.joint: float(trace.y[-1] - trace.setpoint[-1]) for trace in traces}
    path = tip = None
    if plan.arm is not None and plan.line is not None:
        by_joint = {trace.joint: trace.y for trace in traces}
        missing = [name for name in plan.arm.joints if name not in by_joint]
        if missing:
            raise ConfigurationError(f"the line needs a model of joint {', '.join(missing)}")
        tip = plan.arm.forward_many(by_joint[plan.arm.joints[0]], by_joint[plan.arm.joints[1]])
        path = 1000.0 * distance_to_segment(*tip, *plan.line)
    return TrajectoryRun(traces, (start_at, end), rms, final, path, tip)


def run_trajectory(args: argparse.Namespace) -> Outcome:
    """Run ``closed-loop --trajectory``."""
    if args.y0 is not None:
        raise ConfigurationError('--y0 goes with --setpoints; with --trajectory the joints '
                                 'start at its first point')
    models = [load_model(path) for path in args.model]
    names = [model.joint for model in models]
    if len(set(names)) != len(names):
        raise ConfigurationError(f'two models of the same joint: {names}')
    if args.controller and len(args.controller) != len(models):
        raise ConfigurationError(f'give one controller per model ({len(models)}), got '
                                 f'{len(args.controller)}')
    period = control_period_on(args.control_period, args.sample_period).seconds
    specs = [controller_for(model, path, period)
             for model, path in zip(models, args.controller or [None] * len(models))]
    plan = load_trajectory(args.trajectory, args.kinematics)
    total = int(round((args.start_at + plan.trajectory.duration + args.settle)
                      / args.sample_period)) + 1
    with ProgressBar('closed loop', total * len(models)) as bar:
        result = simulate_trajectory(models, specs, plan, dt=args.sample_period,
                                     start_at=args.start_at, settle=args.settle,
                                     feedforward=args.feedforward, noise_std=args.noise,
                                     seed=args.seed, margin=args.setpoint_margin, bar=bar)
    traces = result.traces
    records = [Record(trace.t + args.sample_period, trace.v, trace.measured, joint=trace.joint)
               for trace in traces]
    bag = write_bag(args.out, records, storage=args.storage,
                    setpoints={trace.joint: trace.setpoint for trace in traces})
    payload: dict[str, object] = {
        'bag': str(bag), 'samples': len(records[0]), 'joints': names,
        'feedforward': bool(args.feedforward),
        'motion': list(result.motion), 'rms_error': result.rms_error,
        'final_error': result.final_error,
    }
    lines = [f'trajectory of joints {", ".join(names)}: motion from {result.motion[0]:g} to '
             f'{result.motion[1]:g} s, control every {specs[0].control_period:g} s, '
             f"feed-forward {'on' if args.feedforward else 'off'}"]
    lines += result.error_table()
    in_motion = result.path_in_motion()
    if in_motion is not None:
        worst, spread = in_motion
        path: dict[str, float] = {'max': worst, 'rms': spread}
        payload['path_error_mm'] = path
        lines.append(f'tip distance from the line in motion: max {worst:.1f} mm, '
                     f'RMS {spread:.1f} mm')
        after = result.path_after_motion()
        if after is not None:
            path['after_motion'] = after
            lines.append(f'after the motion ended (t > {result.motion[1]:.2f} s), while the '
                         f'joints settle at the end point: max {after:.1f} mm')
    if args.plot:
        from hydro_sdp.plots import plot_closed_loop, save_figure
        from hydro_sdp.plots.bucket_line import plot_bucket_line

        if result.tip is not None and result.path_error_mm is not None and \
                plan.line is not None:
            figure = plot_bucket_line(*result.tip, plan.line, result.path_error_mm, traces,
                                      result.motion,
                                      title='PIP-IDZ control: bucket tip on a straight line')
        else:
            figure = plot_closed_loop(traces, title='PIP-IDZ control along a trajectory')
        payload['plot'] = str(save_figure(figure, args.plot))
    lines.append(f'wrote {bag}')
    if args.plot:
        lines.append(f'wrote {payload["plot"]}')
    return Outcome(payload, lines)

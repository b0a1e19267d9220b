"""The demo's straight bucket path: boom and dipper drive the bucket tip along a line."""

from __future__ import annotations

from hydro_sdp.cli.demo.report import Report
from hydro_sdp.cli.trajectory_loop import simulate_trajectory
from hydro_sdp.core.control.controller_spec import design_from_model
from hydro_sdp.core.errors import DataError
from hydro_sdp.core.model.timing import SamplePeriod
from hydro_sdp.io.documents import shipped_config
from hydro_sdp.io.model_files import load_model
from hydro_sdp.io.trajectory_files import load_trajectory
from hydro_sdp.plots.bucket_line import plot_bucket_line
import numpy as np

#: Plant sample period and control period, s.
SAMPLE_PERIOD, CONTROL_PERIOD = SamplePeriod(0.02), SamplePeriod(0.1)
#: Hold before the line and time after it, s.
START_AT, SETTLE = 1.0, 4.0


def bucket_line(report: Report) -> None:
    """Run the LUCIE-like boom and dipper along ``config/lucie_line.yaml`` and report it."""
    models = [load_model(shipped_config(f'lucie_{name}.yaml')) for name in ('boom', 'dipper')]
    specs = [design_from_model(model, control_period=CONTROL_PERIOD) for model in models]
    plan = load_trajectory(shipped_config('lucie_line.yaml'))
    if plan.arm is None or plan.line is None:
        raise DataError('config/lucie_line.yaml must be a line with its kinematics')
    run = simulate_trajectory(models, specs, plan, dt=SAMPLE_PERIOD, start_at=START_AT,
                              settle=SETTLE, feedforward=True)
    path, in_motion = run.path_error_mm, run.path_in_motion()
    if path is None or in_motion is None or run.tip is None:
        raise DataError('the bucket line run measured no path error')
    worst, rms = in_motion
    (x0, z0), (x1, z1) = plan.line
    figure = report.figure(plot_bucket_line(
        *run.tip, plan.line, path, run.traces, run.motion,
        title='Bucket tip on an oblique straight line (LUCIE paper, Fig. 7 style)'),
        'bucket_line.png')
    rows = [[trace.joint, f'{run.rms_error[trace.joint]:.3f}',
             f'{run.final_error[trace.joint]:+.3f}'] for trace in run.traces]
    length = float(np.hypot(x1 - x0, z1 - z0))
    report.lines += ['', f'bucket tip on a straight line ({length:.2f} m in '
                     f'{run.motion[1] - run.motion[0]:.1f} s): path error max {worst:.2f} mm, '
                     f'RMS {rms:.2f} mm']
    report.lines += run.error_table()
    report.sections.append('\n'.join([
        '## A straight bucket path', '',
        f'The boom and dipper follow the joint trajectory that keeps the bucket tip on the '
        f'oblique line from ({x0:g}, {z0:g}) m to ({x1:g}, {z1:g}) m, {length:.2f} m in '
        f'{run.motion[1] - run.motion[0]:.1f} s (`config/lucie_line.yaml`, planar two-link '
        "kinematics in `config/lucie_kinematics.yaml`), as in the LUCIE paper's path-tracking "
        f'test. Control every {CONTROL_PERIOD:g} s with the set-point rate fed forward '
        'through the IDZ. Distance of the tip from the line during the motion: max '
        f'**{worst:.2f} mm**, RMS {rms:.2f} mm.', '',
        '| joint | RMS error in motion (deg) | final error (deg) |', '|---|---|---|',
        *[f'| {" | ".join(r)} |' for r in rows], '', f'![bucket line]({figure})', '']))
    report.payload['bucket_line'] = {
        'motion': list(run.motion), 'path_error_mm': {'max': worst, 'rms': rms},
        'rms_error': run.rms_error, 'final_error': run.final_error}

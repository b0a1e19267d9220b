"""The stages of ``hydro-sdp demo``, each adding its part of the report folder."""

from __future__ import annotations

from pathlib import Path
from typing import Callable

from hydro_sdp.bags import read_bag, write_bag
from hydro_sdp.cli.common import table
from hydro_sdp.cli.demo.line import bucket_line
from hydro_sdp.cli.demo.report import Report
from hydro_sdp.core.control.controller_spec import design_from_model, format_pole
from hydro_sdp.core.control.idz import InverseDeadZone
from hydro_sdp.core.control.loop_simulation import (
    LoopJoint, run_closed_loop, step_metrics, step_setpoints)
from hydro_sdp.core.diagnosis import diagnose
from hydro_sdp.core.errors import DataError
from hydro_sdp.core.identification.evaluation import evaluate, simulated_angles
from hydro_sdp.core.identification.identify import identify
from hydro_sdp.core.model.effects import ValveLag
from hydro_sdp.core.model.records import Record
from hydro_sdp.core.model.timing import SamplePeriod
from hydro_sdp.core.synthetic.joint_experiments import experiment_record
from hydro_sdp.io.controller_files import save_controller
from hydro_sdp.io.documents import shipped_config
from hydro_sdp.io.model_files import default_model_path, load_model, save_model
from hydro_sdp.plots import (
    command_unit_of, plot_closed_loop, plot_gains, plot_idz, plot_recalibration, plot_record,
    plot_step_responses, plot_velocity_map)
from hydro_sdp.report.diagnosis import write_report
import numpy as np


def _experiments(report: Report) -> None:
    model = load_model(default_model_path())
    steps = experiment_record(model, 'steps', seed=report.seed,
                              duration=60.0 if report.short else None)
    runs = [experiment_record(model, 'random', seed=report.seed + index,
                              duration=30.0 if report.short else 60.0)
            for index in range(1, 4)]
    bags = {'steps': write_bag(report.out / 'steps_bag', [steps])}
    for index, run in enumerate(runs, start=1):
        bags[f'random_{index}'] = write_bag(report.out / f'random_bag_{index}', [run])
    figures = [report.figure(plot_record(steps, model, title='J2 step experiments (simulated)'),
                             'steps.png')]
    rows = [[name, Path(str(bag)).name, str(len(record)), f'{record.duration:.1f}']
            for (name, bag), record in zip(bags.items(), [steps] + runs)]
    report.lines += ['experiments'] + table(rows, ['program', 'bag', 'samples', 'seconds'])
    report.sections.append('\n'.join([
        '## Experiments', '',
        f'The J2 model (kind {model.kind}, delay {model.delay} s, dead-zone '
        f'{list(model.dead_zone or [])} V) driven open loop, 0.03 deg measurement noise: step '
        'experiments for identification, random-level runs for evaluation.', '',
        '| program | bag | samples | seconds |', '|---|---|---|---|',
        *[f'| {r[0]} | `{r[1]}` | {r[2]} | {r[3]} |' for r in rows], '',
        *[f'![{Path(f).stem}]({f})' for f in figures], '']))
    report.payload['bags'] = {name: str(bag) for name, bag in bags.items()}


def _identification(report: Report) -> None:
    truth = load_model(default_model_path())
    bags = report.payload['bags']
    steps = read_bag(bags['steps']).record()
    result = identify([steps], angle_limits=truth.angle_limits,
                      input_limits=truth.input_limits)
    model = result.model
    save_model(model, report.out / 'j2_identified.yaml')
    report.identified = model
    true_alpha, alpha = truth.alpha(0.01), model.alpha(result.sample_period)
    names = ['alpha_1', 'alpha_2', 'alpha_3', 'alpha_4', 'alpha_5', 'alpha_6', 'delay (s)']
    values = list(zip(names, list(true_alpha) + [truth.delay], list(alpha) + [model.delay]))
    rows = [[name, f'{want:.4f}', f'{got:.4f}', f'{100 * (got - want) / abs(want):+.3f}']
            for name, want, got in values]
    runs = [read_bag(bags[name]).record() for name in bags if name.startswith('random')]
    scores = evaluate(runs, model)
    table_2 = [[str(index), f'{s.model:.3f}', f'{s.sdp_dz:.3f}', f'{s.linear:.3f}']
               for index, s in enumerate(scores, start=1)]
    means = [float(np.mean([getattr(s, key) for s in scores]))
             for key in ('model', 'sdp_dz', 'linear')]
    table_2.append(['mean'] + [f'{m:.3f}' for m in means])
    moving = [p for p in result.points if p.level != result.segmentation.rest]
    figures = [
        report.figure(plot_step_responses(result.segmentation.experiments, result.delay.samples,
                                          result.sample_period), 'step_responses.png'),
        report.figure(plot_gains(result.points, model, result.sample_period), 'gains.png'),
        report.figure(plot_velocity_map(
            model, v_range=(-6.0, 6.0), points=(np.array([p.level for p in moving]),
                                                np.array([p.speed for p in moving])),
            title='Identified J2 velocity map (West et al. 2018, Fig. 3)'), 'velocity_map.png'),
        report.figure(plot_record(runs[0], model, simulated=simulated_angles(model, runs[0]),
                                  title='Model evaluation (West et al. 2018, Fig. 4)'),
                      'evaluation.png')]
    used = len(result.segmentation.experiments)
    report.lines += ['', f'identification ({result.fit.method}, {used} step experiments)']
    report.lines += table(rows, ['coefficient', 'true', 'identified', 'error (%)'])
    report.lines += ['', 'evaluation on random-level runs (MAE, deg; Table 2)']
    report.lines += table(table_2, ['run', 'SDP', 'SDP-DZ', 'linear'])
    report.sections.append('\n'.join([
        '## Identification', '',
        f'{len(result.segmentation.experiments)} step experiments, delay '
        f'{result.delay.samples} samples (onset {result.delay.onset}, cross-correlation '
        f'{result.delay.xcorr}), map fitted by regret-regression (beta = '
        f'{result.fit.beta:.3f}). Coefficients at 0.01 s against the true J2 values:', '',
        '| coefficient | true | identified | error (%) |', '|---|---|---|---|',
        *[f'| {" | ".join(r)} |' for r in rows], '',
        '## Evaluation (Table 2)', '',
        'Mean absolute simulation error (deg) on random-level runs: the identified model, its '
        'SDP-DZ linearisation and the linear model with its gain optimised per run.', '',
        '| run | SDP | SDP-DZ | linear |', '|---|---|---|---|',
        *[f'| {" | ".join(r)} |' for r in table_2], '',
        *[f'![{Path(f).stem}]({f})' for f in figures], '']))
    report.payload['identification'] = {
        'alpha': list(alpha), 'true_alpha': list(true_alpha), 'delay': model.delay,
        'mae': {'model': means[0], 'sdp_dz': means[1], 'linear': means[2]}}


def _control(report: Report) -> None:
    model = load_model(default_model_path())
    # The controller comes from the identified model; the plant is the true joint.
    spec = design_from_model(report.model(), poles=[0.94 + 0.05j, 0.94 - 0.05j, 0.0, 0.0],
                             v_range=(-2.2, 1.75), u_limits=(-2.5, 2.5))
    save_controller(spec, report.out / 'j2_controller.yaml')
    idz = spec.idz
    if not isinstance(idz, InverseDeadZone):
        raise DataError("the J2 design has the paper's chord inverse dead-zone")
    levels = [20.0, 10.0, 55.0]
    hold = 6.0 if report.short else 10.0
    trace = run_closed_loop([LoopJoint(model, spec.controller(),
                                       step_setpoints(levels, hold, SamplePeriod(0.01)), 0.0)],
                            dt=SamplePeriod(0.01), control_period=spec.control_period,
                            noise_std=0.01, seed=report.seed)[0]
    write_bag(report.out / 'closed_loop_bag',
              [Record(trace.t + 0.01, trace.v, trace.measured, joint=model.joint)],
              setpoints={model.joint: trace.setpoint})
    metrics = step_metrics(trace, initial=0.0)
    figures = [report.figure(plot_idz(model, idz, 0.05, u_limits=spec.u_limits),
                             'idz.png'),
               report.figure(plot_closed_loop(
                   [trace], title='J2 PIP-IDZ control (West et al. 2018, Fig. 7)',
                   command_unit=command_unit_of(model)),
                   'closed_loop.png')]
    gains = spec.gains
    rows = [[f'{m.size:+.0f}', f'{m.settling_time:.2f}', f'{m.overshoot:.2f}',
             f'{m.steady_error:+.3f}'] for m in metrics]
    report.lines += ['', f'PIP-IDZ design: f0 {gains.f[0]:.4f}, g {gains.g[0]:.4f} '
                     f'{gains.g[1]:.4f}, kI {gains.k_i:.4f}; IDZ slopes '
                     f'{idz.slopes[0]:.4f} {idz.slopes[1]:.4f}']
    report.lines += table(rows, ['step (deg)', 'settling (s)', 'overshoot (%)',
                                 'steady error (deg)'])
    report.sections.append('\n'.join([
        '## PIP-IDZ control', '',
        f'Poles {", ".join(format_pole(p) for p in spec.poles)} at 0.05 s give '
        f'f0 = {gains.f[0]:.4f}, g1 = {gains.g[0]:.4f}, g2 = {gains.g[1]:.4f}, '
        f'kI = {gains.k_i:.4f} (the paper prints 0.1261, 0.12, 0.1261, 0.0061). IDZ slopes '
        f'{idz.slopes[0]:.4f} and {idz.slopes[1]:.4f} deg per sample per V; u within '
        '+-2.5. Plant at 0.01 s, controller at 0.05 s, 0.01 deg noise; settling into +-0.5 deg.',
        '', '| step (deg) | settling (s) | overshoot (%) | steady error (deg) |',
        '|---|---|---|---|', *[f'| {" | ".join(r)} |' for r in rows], '',
        *[f'![{Path(f).stem}]({f})' for f in figures], '']))
    report.payload['control'] = {
        'f': list(gains.f), 'g': list(gains.g), 'kI': gains.k_i,
        'steps': [{'size': m.size, 'settling_time': m.settling_time, 'overshoot': m.overshoot,
                   'steady_error': m.steady_error} for m in metrics]}


def _two_joints(report: Report) -> None:
    dt, period = SamplePeriod(0.02), SamplePeriod(0.1)
    t = np.arange(0.0, 30.0 if report.short else 40.0, dt)
    ramps = {'boom': np.interp(t, [0, 3, 18, 40], [0.0, 0.0, 30.0, 30.0]),
             'dipper': np.interp(t, [0, 3, 18, 40], [-100.0, -100.0, -60.0, -60.0])}
    joints = []
    for name in ('boom', 'dipper'):
        model = load_model(shipped_config(f'lucie_{name}.yaml'))
        spec = design_from_model(model, control_period=period)
        joints.append(LoopJoint(model, spec.controller(), ramps[name], ramps[name][0]))
    traces = run_closed_loop(joints, dt=dt, control_period=period)
    figure = report.figure(plot_closed_loop(traces, command_unit='drive-demand',
                                            title='Boom and dipper tracking simultaneous ramps'),
                           'two_joints.png')
    rows = []
    for trace in traces:
        late = np.abs(trace.y - trace.setpoint)[trace.t > t[-1] - 5.0]
        rows.append([trace.joint, f'{np.max(np.abs(trace.y - trace.setpoint)):.2f}',
                     f'{np.max(late):.3f}'])
    report.lines += ['', 'two LUCIE-like joints, ramps at 0.1 s control']
    report.lines += table(rows, ['joint', 'max error (deg)', 'error, last 5 s (deg)'])
    report.sections.append('\n'.join([
        '## Two joints at once', '',
        'Boom and dipper of a LUCIE-like excavator (illustrative models, unit delay at 0.1 s, '
        'commands in +-1000 drive-demand units), each with its own model and controller, '
        'follow simultaneous ramps. PIP lags a ramp by f0 r / kI and catches up when it ends.',
        '', '| joint | max error (deg) | error in the last 5 s (deg) |', '|---|---|---|',
        *[f'| {" | ".join(r)} |' for r in rows], '', f'![two joints]({figure})', '']))


def _diagnosis(report: Report) -> None:
    # The 'measured' joint has a valve lag that the identified model does not know about.
    truth = load_model(default_model_path()).with_effect(ValveLag(0.12))
    duration = 40.0 if report.short else 90.0
    records = [experiment_record(truth, 'random', seed=report.seed + 10 + index,
                                 duration=duration) for index in range(3)]
    for index, record in enumerate(records, start=1):
        write_bag(report.out / f'lagged_bag_{index}', [record])
    model = report.model()
    result = diagnose(records[:2], model, validation=records[2:])
    save_model(result.model, report.out / 'j2_augmented.yaml')
    folder = report.out / 'diagnosis'
    write_report(folder, result)
    rows = [[str(i), step.effect, f'{step.mae_before:.3f}', f'{step.mae_after:.3f}']
            for i, step in enumerate(result.ledger, start=1)]
    report.lines += ['', f'diagnosis of a joint with a hidden valve lag: named {result.effect}']
    report.lines += table(rows, ['step', 'effect', 'MAE before', 'MAE after'])
    report.sections.append('\n'.join([
        '## Diagnosis', '',
        'A "measured" J2 joint whose valve has a first-order lag of 0.12 s, held against the '
        f'identified model. Named effect: **{result.effect}**; validation MAE '
        f'{result.mae_before:.3f} deg before, {result.mae_after:.3f} deg after.', '',
        '| step | effect | MAE before (deg) | MAE after (deg) |', '|---|---|---|---|',
        *[f'| {" | ".join(r)} |' for r in rows], '',
        '![gap](diagnosis/gap.png)', '![signature](diagnosis/signature.png)',
        '![ledger](diagnosis/ledger.png)', '',
        'The full report is in `diagnosis/summary.md`.', '']))
    report.payload['diagnosis'] = {'effect': result.effect, 'mae_before': result.mae_before,
                                   'mae_after': result.mae_after,
                                   'ledger': [s.effect for s in result.ledger]}


def _ros_nodes(report: Report) -> None:
    # Imported here, so that the rest of the demo runs where rclpy is not installed.
    try:
        from hydro_sdp.ros.scenarios import wear_and_recalibration
    except ImportError as error:
        report.lines += ['', f'ROS nodes skipped: {error}']
        report.sections.append(f'## The ROS nodes\n\nSkipped: {error}.\n')
        return

    holds, steps, drift_at = (10, 400, 3) if report.short else (20, 400, 5)
    run = wear_and_recalibration(holds=holds, steps=steps, drift_at=drift_at,
                                 seed=report.seed)
    recalibrations = run.recalibrations
    final_edges = tuple(run.edges[-1])
    worst = np.abs(run.angle - run.setpoint).reshape(holds, steps)[:, -50:].max(axis=1)
    figure = report.figure(plot_recalibration(run.t, run.angle, run.setpoint, run.command,
                                              run.edges, run.drift_time), 'recalibration.png')
    before, during, after = worst[:drift_at].max(), worst[drift_at:drift_at + 2].max(), \
        worst[-4:].max()
    report.lines += ['', 'three ROS nodes in-process: the dead-zone narrows by 0.3 V, the '
                     f'identifier recalibrated the controller {recalibrations} times']
    report.lines += table([['before the drift', f'{before:.2f}'],
                           ['just after it', f'{during:.2f}'],
                           ['after recalibration', f'{after:.2f}']],
                          ['tracking', 'error at the end of each hold (deg)'])
    report.sections.append('\n'.join([
        '## The ROS nodes and automatic recalibration', '',
        'plant_node, controller_node and identifier_node run in one process on simulated '
        'time (the launch-free harness). Set-points change every 4 s; at '
        f"{drift_at * 4} s the plant's dead-zone narrows by 0.3 V on both sides (wear), the "
        'IDZ now over-compensates and the loop hunts. The identifier detects the change, '
        f"and with auto_recalibrate it set the controller's IDZ {recalibrations} times; "
        f'the edges end at [{final_edges[0]:.3f}, {final_edges[1]:.3f}] V (true '
        f'[{-1.3298 + 0.3:.3f}, {1.3124 - 0.3:.3f}]).', '',
        '| tracking | worst error at the end of a hold (deg) |', '|---|---|',
        f'| before the drift | {before:.2f} |', f'| just after it | {during:.2f} |',
        f'| after recalibration | {after:.2f} |', '', f'![recalibration]({figure})', '']))
    report.payload['recalibration'] = {
        'recalibrations': recalibrations, 'edges': list(final_edges),
        'error_before': float(before), 'error_after_drift': float(during),
        'error_recalibrated': float(after),
        'seconds_to_recalibration': float(run.time_to_recalibration)}


STAGES: list[tuple[str, Callable[[Report], None]]] = [
    ('experiments', _experiments),
    ('identification', _identification),
    ('control', _control),
    ('two joints', _two_joints),
    ('bucket line', bucket_line),
    ('ROS nodes', _ros_nodes),
    ('diagnosis', _diagnosis),
]

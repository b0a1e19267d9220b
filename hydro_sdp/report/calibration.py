"""The calibration report: velocity map, evaluation, diagnosis, closed-loop check, summary.md."""

from __future__ import annotations

import math
from pathlib import Path

from hydro_sdp.core.calibration import CalibrationResult
from hydro_sdp.core.control.loop_chatter import MAX_PULSE_RATE
from hydro_sdp.core.control.loop_simulation import LoopTrace
from hydro_sdp.core.identification.evaluation import simulated_angles
from hydro_sdp.io.atomic import atomic_write_text
from hydro_sdp.io.model_files import dump_model
from hydro_sdp.plots import (
    plot_closed_loop, plot_record, plot_velocity_map, save_figure)
from hydro_sdp.report.diagnosis import write_report as write_diagnosis
import numpy as np


def _seconds(value: float) -> str:
    return 'never' if not math.isfinite(value) else f'{value:.2f}'


def _velocity_map(folder: Path, result: CalibrationResult, unit: str) -> Path:
    identified = result.identification
    rest = identified.segmentation.rest
    moving = [p for p in identified.points if p.level != rest]
    levels = [p.level for p in moving] or [rest - 1.0, rest + 1.0]
    span = max(max(levels) - min(levels), 1e-6)
    return save_figure(plot_velocity_map(
        result.model, v_range=(min(levels) - 0.1 * span, max(levels) + 0.1 * span),
        points=(np.array([p.level for p in moving]), np.array([p.speed for p in moving])),
        command_unit=unit,
        title=f'Velocity map of joint {result.model.joint} and the level speeds'),
        folder / 'velocity_map.png')


def chatter_lines(result: CalibrationResult, unit: str) -> list[str]:
    """Return the lines on the valve's work at hold and the trade of settling against chatter."""
    chatter = result.check.chatter
    if chatter.travel_bound is None:
        return ['The map has no dead-zone: the valve cannot pulse across one.', '']
    share = chatter.travel_share
    lines = [
        f'Valve at hold (after each step settled, {chatter.duration:.1f} s in all): '
        f'{chatter.pulse_rate:.2f} pulses/s across the dead-zone (bound '
        f'{MAX_PULSE_RATE:g}/s; triangles on the valve panel of the figures), travel '
        f'{chatter.travel_rate:.3g} {unit}/s'
        + ('' if share is None else f' ({100.0 * share:.0f} % of the valve range)')
        + f' (bound {chatter.travel_bound:.3g} {unit}/s, two dead-zone widths).', '']
    if result.trade:
        rows = [f'| {"fade-in " + format(f.fade, ".3g") if f.fade else "chatter band alone"} | '
                f'{_seconds(f.settling[0])}-{_seconds(f.settling[1])} | {f.overshoot:.1f} | '
                f'{f.pulse_rate:.2f} | {f.travel_rate:.3g} | '
                f'{"passed" if f.passed else "FAILED"} |' for f in result.trade]
        lines += ['The first IDZ pulsed at hold; its compensation now fades in beyond the '
                  'chatter band (methods.md section 5.2). The trade, settling against chatter:',
                  '', '| IDZ | settling (s) | overshoot (%) | pulses/s | travel '
                  f'({unit}/s) | check |', '|---|---|---|---|---|---|', *rows, '']
    return lines


def plausible_lines(result: CalibrationResult) -> list[str]:
    """Return the table of the check over the models the data do not rule out."""
    plausible = result.plausible
    if plausible is None or not plausible.checks:
        return []
    rows = []
    for model, check in plausible.checks:
        low, high = check.settling_range
        worst_overshoot = max((m.overshoot for m in check.steps), default=0.0)
        rows.append(f'| {model.name} | {_seconds(low)}-{_seconds(high)} | '
                    f'{worst_overshoot:.1f} | {check.chatter.pulse_rate:.2f} | '
                    f'{"passed" if check.passed else "FAILED: " + "; ".join(check.failures)} |')
    return ['The same controller on the models the data do not rule out, one change each '
            '(methods.md section 5.8; the worst settling dash-dot in the steps figure):', '',
            '| model | settling (s) | overshoot (%) | pulses/s | check |',
            '|---|---|---|---|---|', *rows, '']


def worst_trace(result: CalibrationResult) -> tuple[LoopTrace, str] | None:
    """Return the steps trace of the plausible model that settles last, and its name."""
    if result.plausible is None or not result.plausible.checks:
        return None
    model, check = max(result.plausible.checks, key=lambda pair: (
        not pair[1].passed, pair[1].settling_range[1]))
    return check.steps_trace, model.name


def summary_lines(result: CalibrationResult, unit: str, figures: list[str]) -> list[str]:
    """
    Return the lines of ``summary.md``.

    ``figures``: figure paths relative to the report folder.
    """
    model, spec, check = result.model, result.spec, result.check
    identified = result.identification
    diagnosis = result.diagnosis
    segmentation = identified.segmentation
    dead_zone = model.dead_zone
    steps = [f'| {m.size:+.2f} | {_seconds(m.settling_time)} | {bound:.1f} | '
             f'{m.overshoot:.1f} | {m.steady_error:+.3f} |'
             for m, bound in zip(check.steps, check.bounds)]
    ledger = [f'| {i} | {s.effect} | {s.mae_before:.4g} | {s.mae_after:.4g} |'
              for i, s in enumerate(diagnosis.ledger, start=1)]
    forms = result.forms or ('chord',) * len(result.designs)
    fades = result.fades or (0.0,) * len(result.designs)
    designs = [f'{i}. {form} IDZ{f" fading in over {fade:.3g}" if fade else ""}; '
               f'poles {", ".join(poles)}'
               for i, (poles, form, fade) in enumerate(zip(result.designs, forms, fades),
                                                       start=1)]
    plant = (f'the integrator with {spec.delay_samples} samples of delay'
             + ('' if spec.valve_lag is None else f' and a valve lag of {spec.valve_lag:.3g} s')
             + ('' if spec.oscillation is None else
                f' and a link mode of {spec.oscillation[0]:.3g} Hz, damping '
                f'{spec.oscillation[1]:.2g}'))
    obstacles = [f'| {o.element} | {o.idealised} | '
                 f'{"passes" if o.passed else f"{o.failures} failures"} |'
                 for o in result.obstacles]
    in_the_way = ([] if check.passed or not obstacles else [
        'What stands in the way: the check run again with each element idealised (the map '
        'made the one the IDZ inverts, the delay one control sample, no valve lag, no angle '
        'noise, no other effects; a new delay or lag is designed for again, with the same '
        'dominant poles):', '', '| element | idealised | check |', '|---|---|---|',
        *obstacles, '',
        f'In the way: **{" and ".join(result.in_the_way) or "no element alone"}**.', ''])
    return [
        f'# Calibration of joint `{model.joint}`', '',
        f'Model `{model.kind}` with delay {model.delay:g} s'
        + (f', dead-zone [{dead_zone[0]:.4g}, {dead_zone[1]:.4g}] {unit}' if dead_zone else '')
        + f'; named effect **{result.effect}**; controller at {spec.control_period:g} s; '
        f'closed-loop check **{"passed" if check.passed else "FAILED"}**.', '',
        '## Warnings', '', *([f'- {w}' for w in result.warnings] or ['none']), '',
        '## Identification', '',
        f'{len(result.estimation)} record(s): {len(segmentation.experiments)} experiments '
        f'({segmentation.steps} steps, {segmentation.runs} runs), {len(segmentation.dropped)} '
        f'segments dropped, rest command {segmentation.rest:g} {unit}, sample period '
        f'{identified.sample_period:g} s, noise {segmentation.noise_std:.3g} deg. Delay '
        f'{identified.delay.samples} samples; effects found: '
        f'{", ".join(e.name for e in identified.model.effects) or "none"}. Map family chosen '
        'on held-out experiments:', '',
        '| kind | held-out MAE (deg) |', '|---|---|',
        *[f'| {s.kind} | {s.mae:.4g} |' for s in identified.comparison], '',
        '## Evaluation', '',
        f'Validation records ({result.validation_note}): mean per-record simulation MAE '
        f'{result.mae_identified:.4g} deg for the identified model, {result.mae_final:.4g} deg '
        'for the final model (the diagnosis keeps an effect only if this MAE shrinks, so '
        'the final figure is not independent of them).', '',
        '## Diagnosis', '',
        '| step | effect | MAE before (deg) | MAE after (deg) |', '|---|---|---|---|',
        *(ledger or ['| - | none | - | - |']), '',
        'The full discrepancy report is in `diagnosis/summary.md`.', '',
        '## Controller and closed-loop check', '',
        f'Designed on {plant} at {spec.control_period:g} s. Designs tried (IDZ form and '
        'closed-loop poles, first to last):', '', *designs, '',
        f'The controller runs on the final model, with its effects, from 20 % of the stroke '
        f'[{result.stroke[0]:.4g}, {result.stroke[1]:.4g}] deg to 50 %, 80 %, 50 % and 20 %, '
        'then along a ramp from 20 % to 80 % at a quarter of full speed. Settling into '
        f'+-0.5 deg within the bound (6 s plus the travel at a quarter of full speed), '
        'overshoot at most 10 %, no limit cycle; the controller reads the angle with the '
        f'noise found in the records ({segmentation.noise_std:.3g} deg).', '',
        '| step (deg) | settling (s) | bound (s) | overshoot (%) | steady error (deg) |',
        '|---|---|---|---|---|', *steps, '',
        f'Ramp: largest tracking error {check.ramp_error:.3g} deg, settled '
        f'{_seconds(check.ramp_settling)} s after its end; holds ending in a limit cycle: '
        f'{check.cycles}.', '', *chatter_lines(result, unit),
        *[f'- {failure}' for failure in check.failures], '',
        *plausible_lines(result),
        *in_the_way,
        '## Figures', '', *[f'![{Path(f).stem}]({f})' for f in figures], '',
        '## Final model', '', '```yaml', dump_model(model).rstrip(), '```', '']


def write_report(folder: Path, result: CalibrationResult, unit: str) -> list[str]:
    """Write the figures and ``summary.md`` of a calibration."""
    record = result.validation[0]
    name = record.source or 'first'
    edges = result.check.chatter.edges
    valve = None if edges is None or result.spec.idz is None else (edges, result.spec.idz.rest)
    written = [
        _velocity_map(folder, result, unit),
        save_figure(plot_record(record, result.model,
                                simulated=simulated_angles(result.model, record),
                                command_unit=unit,
                                title=f'Final model on a validation record ({name})'),
                    folder / 'evaluation.png'),
        save_figure(plot_closed_loop([result.check.steps_trace], command_unit=unit,
                                     title='Closed-loop check: steps across the stroke '
                                           '(final model)', valve=valve,
                                     worst=worst_trace(result)),
                    folder / 'closed_loop.png'),
        save_figure(plot_closed_loop([result.check.ramp_trace], command_unit=unit,
                                     title='Closed-loop check: ramp (final model)',
                                     valve=valve),
                    folder / 'ramp.png')]
    diagnosis = write_diagnosis(folder / 'diagnosis', result.diagnosis, command_unit=unit)
    figures = [f'{Path(p).name}' for p in written] + [
        f'diagnosis/{Path(p).name}' for p in diagnosis if p.endswith('.png')]
    summary = atomic_write_text(folder / 'summary.md',
                                '\n'.join(summary_lines(result, unit, figures)))
    return [str(p) for p in written] + diagnosis + [str(summary)]

"""The discrepancy report: gap, residual signature, SDP evidence, ledger and ``summary.md``."""

from __future__ import annotations

import math
from pathlib import Path

from hydro_sdp.core.diagnosis import Candidate, Diagnosis
from hydro_sdp.core.diagnosis.decision import MARGIN, MOST
from hydro_sdp.io.atomic import atomic_write_text
from hydro_sdp.io.model_files import dump_model
from hydro_sdp.plots import command_unit_of, plot_gap, plot_ledger, plot_signature, save_figure
from hydro_sdp.plots.diagnosis import plot_record_scales
from hydro_sdp.plots.diagnosis_evidence import plot_candidates, plot_state_evidence


def _own(candidate: Candidate) -> str:
    """Return the windowed error on the estimation records without and with the effect."""
    if not math.isfinite(candidate.own_after):
        return '-'
    return f'{candidate.own_before:.3g} -> {candidate.own_after:.3g}'


def _candidate_rows(result: Diagnosis) -> list[str]:
    rows = []
    for c in result.candidates:
        if not c.applicable:
            continue
        state = f'{c.state} ({100 * result.shares.get(c.state, 0.0):.3g} %)' if \
            c.named_by_data else '-'
        rows.append(f'| {c.effect} | {state} | {"yes" if c.accepted else "no"} | '
                    f'{100 * c.held_out:.1f} | {_own(c)} | {100 * c.gain:.1f} | {c.t:.3g} | '
                    f'{c.p_value:.2g} | {c.evidence} |')
    return rows


def write_report(folder: Path, result: Diagnosis, *, command_unit: str | None = None) -> list[str]:
    """
    Write the figures and ``summary.md`` of a diagnosis.

    ``command_unit``: unit of the command for the labels; default: from the model's input range.
    Returns: the paths written: ``gap.png``, ``ledger.png``, ``signature.png`` and ``evidence.png``
    when an effect was named, ``candidates.png``, ``record_scales.png`` for per-record load
    factors, and ``summary.md``.
    """
    gap = result.gap
    unit = command_unit_of(result.model, command_unit)
    figures = [save_figure(plot_gap(gap.t, gap.measured, gap.before, gap.after,
                                    title='Validation run: model given and augmented'),
                           folder / 'gap.png'),
               save_figure(plot_ledger(result.mae_before, result.ledger), folder / 'ledger.png')]
    if result.signature is not None:
        figures.append(save_figure(plot_signature(result.signature, command_unit=unit),
                                   folder / 'signature.png'))
    if result.evidence is not None:
        figures.append(save_figure(plot_state_evidence(result.evidence, command_unit=unit),
                                   folder / 'evidence.png'))
    figures.append(save_figure(plot_candidates(result.candidates, result.effect),
                               folder / 'candidates.png'))
    # Records that differ in speed without a load signal, the lead: each record's scale,
    # the evidence of a word refused for want of its cause.
    for candidate in result.candidates[:1]:
        if candidate.effect == 'load_dependence':
            scales = plot_record_scales(candidate)
            if scales is not None:
                figures.append(save_figure(scales, folder / 'record_scales.png'))
    ledger = [f'| {i} | {s.effect} | {s.mae_before:.4g} | {s.mae_after:.4g} | '
              f'{s.window_before:.4g} | {s.window_after:.4g} |'
              for i, s in enumerate(result.ledger, start=1)]
    added = len(result.ledger)
    signature = result.signature
    reading = []
    if result.evidence is not None:
        reading += [f'`evidence.png`: what the model misses against `{result.evidence.state}`, '
                    f'the state whose SDP estimate named `{result.effect}` (the ratio of the '
                    "measured to the model's increment, 1 when right, and the increment "
                    'residual, 0 when right; +-2 standard errors), for the model given and '
                    'with the effect.', '']
    if signature is not None and signature.x is not None and \
            signature.signs.size == signature.x.size:
        reading += ['The signature draws the velocity residual against the angle for each '
                    'direction of motion apart, signed by the motion (positive: faster than the '
                    'model). A factor of the angle shared by both directions (linkage: '
                    '`stroke_geometry`) shows as one curve twice; a gravity-like one '
                    '(`angle_dependent_velocity`) as two mirrored curves; a stop as the residual '
                    'of one direction at one end.', '']
    shares = ', '.join(f'`{state}` {100 * share:.3g} %' for state, share in
                       sorted(result.shares.items(), key=lambda item: -item[1]))
    summary = '\n'.join([
        '# Discrepancy report', '',
        f'**Named effect: `{result.effect}`.** Validation MAE {result.mae_before:.4g} deg '
        f'before, {result.mae_after:.4g} deg after '
        f'({added} effect{"s" if added != 1 else ""} added; judged on {result.validation}).',
        '', '## Gap ledger', '',
        '| step | effect | MAE before (deg) | MAE after (deg) | windowed before (deg) | '
        'windowed after (deg) |', '|---|---|---|---|---|---|',
        *(ledger or ['| - | none | - | - | - | - |']), '',
        '## What the data name', '',
        'Share of the squared residual each state explains on data it was not fitted to, in '
        f'the SDP analysis of what the model misses: {shares or "not analysed"}.', '',
        '## Candidates (first round)', '',
        'Each word fitted to the estimation records and judged on held-out ones: the share '
        'of the simulation error over 2-second windows from the measured angle it removes '
        f'(a name needs {100 * MARGIN:g} %), the share of the squared velocity residual, and '
        'the block '
        'bootstrap of that reduction (z, p; significant at p <= 0.01). A candidate that '
        f'removes {100 * MOST:g} % of the residual is never dismissed.', '',
        '| effect | named by the data | accepted | held-out error removed (%) | windowed '
        'error on the estimation records (deg) | residual removed (%) | z | p | evidence |',
        '|---|---|---|---|---|---|---|---|---|',
        *_candidate_rows(result), '',
        *[f'Refused: `{c.effect}`: {c.refused}.' for c in result.candidates if c.refused],
        '', '## Figures', '', *reading,
        *[f'![{Path(f).stem}]({Path(f).name})' for f in figures], '',
        '## Augmented model', '', '```yaml', dump_model(result.model).rstrip(), '```', ''])
    atomic_write_text(folder / 'summary.md', summary)
    return [str(f) for f in figures] + [str(folder / 'summary.md')]

"""The discrepancy report: gap, residual signature, gap ledger and ``summary.md``."""

from __future__ import annotations

from pathlib import Path

from hydro_sdp.core.diagnosis import Diagnosis
from hydro_sdp.io.atomic import atomic_write_text
from hydro_sdp.io.model_files import dump_model
from hydro_sdp.plots import command_unit_of, plot_gap, plot_ledger, plot_signature, save_figure
from hydro_sdp.plots.diagnosis import plot_candidates, plot_record_scales


def write_report(folder: Path, result: Diagnosis, *, command_unit: str | None = None) -> list[str]:
    """
    Write the figures and ``summary.md`` of a diagnosis.

    Parameters
    ----------
    folder : Path
        Report folder (created if missing).
    result : Diagnosis
        What :func:`hydro_sdp.core.diagnosis.diagnose` found, with its evidence.
    command_unit : str or None
        Unit of the command for the labels; default: from the model's input range.

    Returns
    -------
    list[str]
        The paths written: ``gap.png``, ``ledger.png``, ``signature.png`` and
        ``candidates.png`` when an effect was named, and ``summary.md``.

    """
    gap = result.gap
    figures = [save_figure(plot_gap(gap.t, gap.measured, gap.before, gap.after,
                                    title='Validation run: model given and augmented'),
                           folder / 'gap.png'),
               save_figure(plot_ledger(result.mae_before, result.ledger), folder / 'ledger.png')]
    if result.signature is not None:
        unit = command_unit_of(result.model, command_unit)
        figures.append(save_figure(plot_signature(result.signature, command_unit=unit),
                                   folder / 'signature.png'))
        figures.append(save_figure(plot_candidates(result.candidates, result.effect),
                                   folder / 'candidates.png'))
    # The evidence of load_dependence, when it was named: each record's scale with errors.
    named = {step.effect for step in result.ledger}
    for candidate in result.candidates:
        if candidate.effect == 'load_dependence' and candidate.effect in named:
            scales = plot_record_scales(candidate)
            if scales is not None:
                figures.append(save_figure(scales, folder / 'record_scales.png'))
    rows = [f'| {c.effect} | {"yes" if c.significant else "no"} | {100 * c.gain:.1f} | '
            f'{c.t:.1f} | {c.evidence} |' for c in result.candidates if c.applicable]
    ledger = [f'| {i} | {s.effect} | {s.mae_before:.4g} | {s.mae_after:.4g} |'
              for i, s in enumerate(result.ledger, start=1)]
    added = len(result.ledger)
    signature = result.signature
    reading = []
    if signature is not None and signature.x is not None and \
            signature.signs.size == signature.x.size:
        reading = ['The signature draws the velocity residual against the angle for each '
                   'direction of motion apart, signed by the motion (positive: faster than the '
                   'model). A factor of the angle shared by both directions (linkage: '
                   '`stroke_geometry`) shows as one curve twice; a gravity-like one '
                   '(`angle_dependent_velocity`) as two mirrored curves; a stop as the residual '
                   'of one direction at one end.', '']
    summary = '\n'.join([
        '# Discrepancy report', '',
        f'**Named effect: `{result.effect}`.** Validation MAE {result.mae_before:.4g} deg '
        f'before, {result.mae_after:.4g} deg after '
        f'({added} effect{"s" if added != 1 else ""} added).', '',
        '## Gap ledger', '', '| step | effect | MAE before (deg) | MAE after (deg) |',
        '|---|---|---|---|', *(ledger or ['| - | none | - | - |']), '',
        '## Candidates (first round)', '',
        'Share of the squared velocity residual each effect removes, and the sign-test '
        'statistic over one-second blocks, (better - worse) / sqrt(better + worse) '
        '(significant: z > 3 and at least 2 %).', '',
        '| effect | significant | gain (%) | z | evidence |', '|---|---|---|---|---|', *rows,
        '', '## Figures', '', *reading, *[f'![{Path(f).stem}]({Path(f).name})' for f in figures],
        '',
        '## Augmented model', '', '```yaml', dump_model(result.model).rstrip(), '```', ''])
    atomic_write_text(folder / 'summary.md', summary)
    return [str(f) for f in figures] + [str(folder / 'summary.md')]

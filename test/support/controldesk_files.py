"""
dSPACE ControlDesk recorder exports (CSV) written as a Windows machine in Korea writes them.

Metadata rows first (a description, the experiment, a date in Korean), then one
section per raster separated by blank rows: ``trace_names`` (``In1`` for a
signal read at a Simulink inport, nothing for the time), ``trace_units``,
``raster``, ``path`` (the block path, ending in the port or not), ``min``,
``max``, and the samples from the row keyed ``trace_values`` on, each with an
empty first cell and the time second. Bytes in CP949 by default (the numbers
ASCII, the metadata not), CRLF line ends.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Sequence

import numpy as np

#: Metadata a Korean ControlDesk installation writes above the sections.
METADATA = ('description,굴착기 암 시험 (excavator arm runs)', 'experiment,Arm_runs_2024',
            'date,2024년 5월 3일 오후 2:11:12')


@dataclass(frozen=True)
class Trace:
    """One recorded signal: its trace name, block path, unit and values."""

    name: str
    path: str
    unit: str
    values: np.ndarray


def _number(value: float, decimal: str) -> str:
    text = repr(float(value))
    return text.replace('.', decimal) if decimal != '.' else text


def controldesk_text(sections: Sequence[tuple[np.ndarray, Sequence[Trace]]], *,
                     delimiter: str = ',', decimal: str = '.', quote: bool = False,
                     trailing: bool = False, metadata: Sequence[str] = METADATA) -> str:
    """
    Return the text of an export.

    Parameters
    ----------
    sections : sequence
        ``(time, traces)`` per raster.
    delimiter, decimal : str
        Cell delimiter and decimal point.
    quote : bool
        Quote every text cell, as some exports do.
    trailing : bool
        End every row with a delimiter (an empty last cell).
    metadata : sequence of str
        Rows above the sections (their own delimiter is a comma, changed to ``delimiter``).

    Returns
    -------
    str
        The export, with LF line ends (the writer turns them into CRLF).

    """
    def row(cells: Sequence[str]) -> str:
        return delimiter.join(cells) + (delimiter if trailing else '')

    def text(cell: str) -> str:
        return f'"{cell}"' if quote and cell else cell

    lines = [row([text(cell) for cell in line.split(',', 1)]) for line in metadata] + ['']
    for t, traces in sections:
        lines += [row([text('trace_names'), ''] + [text(s.name) for s in traces]),
                  row([text('trace_units'), text('s')] + [text(s.unit) for s in traces]),
                  row([text('raster'), '']
                      + [text(f'{1000 * (t[1] - t[0]):.0f} ms')] * len(traces)),
                  row([text('path'), ''] + [text(s.path) for s in traces]),
                  row([text('min'), _number(t[0], decimal)]
                      + [_number(np.min(s.values), decimal) for s in traces]),
                  row([text('max'), _number(t[-1], decimal)]
                      + [_number(np.max(s.values), decimal) for s in traces])]
        for k, time in enumerate(t):
            lines.append(row([text('trace_values') if k == 0 else '', _number(time, decimal)]
                             + [_number(s.values[k], decimal) for s in traces]))
        lines.append('')
    return '\n'.join(lines)


def write_controldesk(path: Path, sections: Sequence[tuple[np.ndarray, Sequence[Trace]]], *,
                      encoding: str = 'cp949', **layout: object) -> Path:
    """Write an export (CRLF line ends) in ``encoding``; ``layout`` as :func:`controldesk_text`."""
    text = controldesk_text(sections, **layout)   # type: ignore[arg-type]
    path.write_bytes(text.replace('\n', '\r\n').encode(encoding))
    return path

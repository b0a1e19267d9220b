"""
CSV logs as channels: one time column, columns by header name or 0-based index.

Loggers write lines of their own above the table (the logger's name, the date,
the sample rate). The header is the last row that names the columns before the
numbers start: the row just above the first row of numbers, when none of its
cells is a number (``--header-row N`` names it instead, numbered as a
spreadsheet numbers rows). Every row after it is a sample. Row numbers in
messages are those a spreadsheet shows: the file's line.

"""

from __future__ import annotations

import csv
from dataclasses import dataclass
import io

from hydro_sdp.core.arrays import FloatArray
from hydro_sdp.core.errors import ConfigurationError, DataError
from hydro_sdp.io.logs.table import Channel, first_time_fault
import numpy as np

#: Delimiters that are awkward to type in a shell, by name.
DELIMITER_NAMES = {'tab': '\t', '\\t': '\t', 'space': ' '}

#: Rows as ``(spreadsheet row number, stripped cells)``.
Rows = list[tuple[int, list[str]]]


@dataclass(frozen=True)
class _Column:
    index: int
    label: str


def delimiter_character(text: str) -> str:
    """
    Return the one-character delimiter that ``text`` names.

    Parameters
    ----------
    text : str
        A single character, or ``tab`` (also a backslash and ``t``) or ``space``.

    Returns
    -------
    str
        The character.

    """
    character = DELIMITER_NAMES.get(text, text)
    if len(character) != 1 or character in '"\r\n':
        raise ConfigurationError(f'delimiter must be one character (or tab, space), '
                                 f'got {text!r}')
    return character


def is_number(cell: str) -> bool:
    """Whether a cell reads as a number."""
    try:
        float(cell)
    except ValueError:
        return False
    return True


def _rows(text: str, delimiter: str, source: str) -> Rows:
    """Rows as ``(spreadsheet row number, stripped cells)``, blank rows left out."""
    reader = csv.reader(io.StringIO(text, newline=''), delimiter=delimiter)
    rows = []
    try:
        for cells in reader:
            stripped = [cell.strip() for cell in cells]
            if any(stripped):
                rows.append((reader.line_num, stripped))
    except csv.Error as error:
        raise DataError(f'{source}: row {reader.line_num}: not CSV ({error})') from None
    return rows


def _numbers(cells: list[str]) -> bool:
    filled = [cell for cell in cells if cell != '']
    return len(filled) >= 2 and all(is_number(cell) for cell in filled)


def split_header(rows: Rows, header_row: int | None,
                 source: str) -> tuple[tuple[int, list[str]] | None, Rows]:
    """
    Find the header and the sample rows.

    Parameters
    ----------
    rows : Rows
        The file's non-blank rows.
    header_row : int or None
        Spreadsheet number of the header row; default: the row above the first
        row of numbers, when none of its cells is a number.
    source : str
        The file, for messages.

    Returns
    -------
    tuple
        ``(header, data)``: the header row (None without one) and the rows after it.

    """
    if header_row is not None:
        at = [i for i, (line, _) in enumerate(rows) if line == header_row]
        if not at:
            raise DataError(f'{source}: --header-row {header_row}: the file has no such '
                            f'row (or it is blank)')
        return rows[at[0]], rows[at[0] + 1:]
    first = next((i for i, (_, cells) in enumerate(rows) if _numbers(cells)), len(rows))
    if first == 0:
        return None, rows
    above = rows[first - 1]
    if any(is_number(cell) for cell in above[1]):
        # A line of the logger's (a rate, a date) right above the numbers: no header.
        return None, rows[first:]
    return above, rows[first:]


class CsvTable:
    """
    The columns of a CSV log, each timed by the time column.

    Parameters
    ----------
    text : str
        The file's content.
    time : str or None
        Time column (header name or 0-based index), s; required.
    delimiter : str
        Cell delimiter (see :func:`delimiter_character`).
    source : str
        The file, for messages.
    header_row : int or None
        Spreadsheet number of the header row (default: found, see the module).
    time_role : str
        How messages name the time option.

    """

    def __init__(self, text: str, time: str | None, *, delimiter: str = ',',
                 source: str = 'csv', header_row: int | None = None,
                 time_role: str = '--time') -> None:
        self.source = source
        rows = _rows(text, delimiter_character(delimiter), source)
        if not rows:
            raise DataError(f'{source}: file is empty')
        header, self.data = split_header(rows, header_row, source)
        self.first_line = rows[0][0]
        self.header = None if header is None else header[1]
        self.header_line = rows[0][0] if header is None else header[0]
        if len(self.data) < 2:
            plural = '' if len(self.data) == 1 else 's'
            raise DataError(f'{source}: {len(self.data)} data row{plural}; a log needs at '
                            'least 2')
        self.width = len(self.header if self.header is not None else self.data[0][1])
        if time is None:
            raise ConfigurationError(f'{source}: a CSV log needs its time column ({time_role})')
        column = self._resolve(time, time_role)
        self.t = self._values(column)
        self._check_time(column)

    def channel(self, name: str, role: str) -> Channel:
        """Return column ``name`` (header name or 0-based index), timed by the time column."""
        column = self._resolve(name, role)
        return Channel(name, self.t, self._values(column), f'column {column.label}')

    def _resolve(self, spec: str, option: str) -> _Column:
        """Find the column a ``--time``/``--angle``/... value names."""
        header, source = self.header, self.source
        if header is not None and spec in header:
            if header.count(spec) > 1:
                raise DataError(f'{source}: row {self.header_line}: {header.count(spec)} columns '
                                f'are named {spec!r} ({option}); choose one by 0-based index')
            return _Column(header.index(spec), f'{spec!r}')
        if spec.isdigit():
            index = int(spec)
            if index >= self.width:
                raise DataError(f'{source}: no column {index} ({option}): the file has '
                                f'{self.width} columns, 0 to {self.width - 1}')
            return _Column(index, f"'{header[index]}'" if header is not None else f'{index}')
        if header is None:
            raise DataError(f'{source}: no column {spec!r} ({option}): the file has no header '
                            'row, choose columns by 0-based index')
        hint = '' if self.header_line == self.first_line else \
            ' (the header is taken from the row above the numbers; name another with ' \
            '--header-row N)'
        raise DataError(f'{source}: row {self.header_line}: no column {spec!r} ({option}); '
                        f"columns: {', '.join(header)}{hint}")

    def _values(self, column: _Column) -> FloatArray:
        """Return the numbers of one column, naming the row and column of a bad cell."""
        cells = []
        for line, row in self.data:
            if column.index >= len(row) or row[column.index] == '':
                raise DataError(f'{self.source}: row {line}, column {column.label}: empty '
                                f'(the row has {len(row)} cells)')
            cells.append(row[column.index])
        try:
            values = np.asarray(cells, dtype=np.float64)
        except ValueError:
            for (line, _), cell in zip(self.data, cells):
                if not is_number(cell):
                    raise DataError(f'{self.source}: row {line}, column {column.label}: '
                                    f'{cell!r} is not a number') from None
            raise
        bad = np.flatnonzero(~np.isfinite(values))
        if bad.size:
            k = int(bad[0])
            more = f' ({bad.size} such cells in the column)' if bad.size > 1 else ''
            raise DataError(f'{self.source}: row {self.data[k][0]}, column {column.label}: '
                            f'{cells[k]!r} is not a finite number{more}')
        return values

    def _check_time(self, column: _Column) -> None:
        t = self.t
        fault = first_time_fault(t)
        if fault is not None:
            k = fault.index
            more = f' ({fault.count} such rows in all)' if fault.count > 1 else ''
            raise DataError(f'{self.source}: row {self.data[k + 1][0]}, column {column.label}: '
                            f'time {t[k + 1]:.9g} s {fault.kind} {t[k]:.9g} s on row '
                            f'{self.data[k][0]}{more}')

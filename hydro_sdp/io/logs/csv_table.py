"""CSV logs as channels: one time column, columns by name or 0-based index."""

from __future__ import annotations

from dataclasses import dataclass

from hydro_sdp.core.arrays import FloatArray
from hydro_sdp.core.errors import ConfigurationError, DataError
from hydro_sdp.io.logs.controldesk import ControlDeskTable, is_controldesk
from hydro_sdp.io.logs.table import Channel, LogTable
from hydro_sdp.io.logs.text_rows import (
    check_time_column, column_values, delimiter_character, is_number, numbers_row, read_rows,
    Rows, sniff_delimiter)

#: A row and its spreadsheet number.
Row = tuple[int, list[str]]


@dataclass(frozen=True)
class _Column:
    index: int
    label: str


@dataclass(frozen=True)
class Header:
    """
    The header block of a CSV log.

    Attributes
    ----------
    others : tuple[Row, ...]
        The block's other rows (units, descriptions), top to bottom.

    """

    names: Row
    others: tuple[Row, ...] = ()


def _header_row(cells: list[str], decimal_comma: bool) -> bool:
    return len(cells) >= 2 and not any(is_number(cell, decimal_comma) for cell in cells)


def split_header(rows: Rows, header_row: int | None, source: str,
                 decimal_comma: bool = False) -> tuple[Header | None, Rows]:
    """
    Find the header block and the sample rows.

    ``rows``: the file's rows, blank ones empty.
    ``header_row``: spreadsheet number of the names row; default: found (docs/interfaces.md section
    4.4).
    ``decimal_comma``: whether a comma in a number is its decimal point.
    Returns: ``(header, data)``: the header block (None without one) and the non-blank rows from
    the first row of numbers on.
    """
    start = 0
    if header_row is not None:
        at = [i for i, (line, cells) in enumerate(rows) if line == header_row and cells]
        if not at:
            raise DataError(f'{source}: --header-row {header_row}: the file has no such '
                            f'row (or it is blank)')
        start = at[0] + 1
    first = next((i for i in range(start, len(rows)) if numbers_row(rows[i][1], decimal_comma)),
                 len(rows))
    data = [row for row in rows[first:] if row[1]]
    if header_row is not None:
        block = [row for row in rows[start - 1:first] if row[1]]
        return Header(block[0], tuple(block[1:])), data
    top = first
    while top > 0 and _header_row(rows[top - 1][1], decimal_comma):
        top -= 1
    block = rows[top:first]
    if not block:
        return None, data
    widest = max(range(len(block)), key=lambda i: (sum(c != '' for c in block[i][1]), -i))
    return Header(block[widest], tuple(row for i, row in enumerate(block) if i != widest)), data


class CsvTable:
    """
    The columns of a CSV log, each timed by the time column.

    ``rows``: the file's rows (:func:`.text_rows.read_rows`).
    ``time``: time column (name or 0-based index), s; required.
    ``header_row``: spreadsheet number of the names row (default: found, see the module).
    ``decimal_comma``: whether a comma in a number is its decimal point.
    ``notes``: what the user should know of how the file was read.
    """

    def __init__(self, rows: Rows, time: str | None, *, source: str = 'csv',
                 header_row: int | None = None, time_role: str = '--time',
                 decimal_comma: bool = False, notes: tuple[str, ...] = ()) -> None:
        self.source = source
        self.notes = notes
        self.decimal_comma = decimal_comma
        filled = [row for row in rows if row[1]]
        if not filled:
            raise DataError(f'{source}: file is empty')
        header, self.data = split_header(rows, header_row, source, decimal_comma)
        self.first_line = filled[0][0]
        self.header = None if header is None else header.names[1]
        self.others = () if header is None else header.others
        self.header_line = self.first_line if header is None else header.names[0]
        if len(self.data) < 2:
            plural = '' if len(self.data) == 1 else 's'
            raise DataError(f'{source}: {len(self.data)} data row{plural}; a log needs at '
                            'least 2')
        self.width = max(len(self.header or ()), len(self.data[0][1]))
        if time is None:
            raise ConfigurationError(f'{source}: a CSV log needs its time column ({time_role})')
        column = self._resolve(time, time_role)
        self.t = self._values(column)
        self._check_time(column)

    def channel(self, name: str, role: str) -> Channel:
        """Return column ``name`` (name or 0-based index), timed by the time column."""
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
            named = header[index] if header is not None and index < len(header) else ''
            return _Column(index, f"'{named}'" if named else f'{index}')
        found = sorted({index for _, cells in self.others
                        for index, cell in enumerate(cells) if cell == spec})
        if len(found) == 1:
            return _Column(found[0], f'{spec!r}')
        if found:
            rows = ', '.join(str(line) for line, cells in self.others if spec in cells)
            raise DataError(f'{source}: row {rows}: {len(found)} columns are named {spec!r} '
                            f'({option}); choose one by its name on row {self.header_line} or '
                            'by 0-based index')
        if header is None:
            raise DataError(f'{source}: no column {spec!r} ({option}): the file has no header '
                            'row, choose columns by 0-based index')
        hint = '' if self.header_line == self.first_line else \
            ' (the names are read from the row above the numbers; name another with ' \
            '--header-row N)'
        encoding = ''.join(f'; {note}' for note in self.notes)
        raise DataError(f'{source}: row {self.header_line}: no column {spec!r} ({option}); '
                        f"columns: {', '.join(header)}{hint}{encoding}")

    def _values(self, column: _Column) -> FloatArray:
        """Return the numbers of one column, naming the row and column of a bad cell."""
        return column_values(self.data, column.index, f'column {column.label}', self.source,
                             self.decimal_comma)

    def _check_time(self, column: _Column) -> None:
        check_time_column(self.t, self.data, f'column {column.label}', self.source)


def text_table(text: str, time: str | None, *, delimiter: str | None = None,
               source: str = 'csv', header_row: int | None = None, time_role: str = '--time',
               notes: tuple[str, ...] = ()) -> LogTable:
    """
    Read a CSV log's text as a ControlDesk export or a plain table, whichever it is.

    ``text``: the file's content.
    ``time``: time column (optional for a ControlDesk export, which names its own).
    ``delimiter``: cell delimiter (see :func:`.text_rows.delimiter_character`); default: sniffed.
    ``header_row``: spreadsheet number of a plain table's names row.
    Returns: the file's channels.
    """
    character = sniff_delimiter(text) if delimiter is None else delimiter_character(delimiter)
    rows = read_rows(text, character, source)
    decimal_comma = character != ','
    if is_controldesk(rows):
        if header_row is not None:
            raise ConfigurationError(f'{source}: a ControlDesk export names its columns in its '
                                     'trace_names and path rows; leave out --header-row')
        return ControlDeskTable(rows, time, source=source, time_role=time_role,
                                decimal_comma=decimal_comma, notes=notes)
    return CsvTable(rows, time, source=source, header_row=header_row, time_role=time_role,
                    decimal_comma=decimal_comma, notes=notes)

"""
CSV logs of one joint, read as records ready to be written as bags.

A logger writes one row per sample: the time (s), the measured angle and the
command it applied at that time. Columns are chosen by header name or by
0-based index; the first row is a header when none of its cells is a number.
Row numbers in messages are those a spreadsheet shows: the file's line, the
header being row 1.

Timing (docs/methods.md section 3.4). A record's ``v_k`` is the command in
force over the interval ``(t_{k-1}, t_k]`` that ends at sample ``t_k``. The
command on row ``k`` is the one the logger applied at ``t_k``, so it is in
force over the interval *after* the row: ``v_{k+1}`` = command of row ``k``,
and the angle of row ``k + 1`` is the first that can show it. Before the first
row the command is taken to be the first row's (rule 3: ``timing.delayed`` by
one sample); the last row's command acts after the last angle and is unused.
Written with :func:`hydro_sdp.bags.write_bag`, the command of row ``k`` is
stamped at ``t_k`` itself, which is what the logger did, and reads back as the
same record.

Time. Only differences of the time column matter: it may start at any value
(logger clock, Unix time, negative). It is shifted so the first row lands one
period ``t_1 - t_0`` after ``t = 0``, where a bag must start (its first
command is stamped one period before the first sample). Irregular steps are
kept as they are; steps that repeat or go backwards are refused.

"""

from __future__ import annotations

import csv
from dataclasses import dataclass
import io
import os
from pathlib import Path

from hydro_sdp.core.arrays import FloatArray
from hydro_sdp.core.errors import ConfigurationError, DataError
from hydro_sdp.core.model.records import Record
from hydro_sdp.core.model.timing import delayed
from hydro_sdp.io.documents import read_text
import numpy as np

#: Units of the angle column.
ANGLE_UNITS = ('deg', 'rad')
#: Delimiters that are awkward to type in a shell, by name.
DELIMITER_NAMES = {'tab': '\t', '\\t': '\t', 'space': ' '}


@dataclass(frozen=True, eq=False)
class CsvLog:
    """
    One CSV log as a record.

    Parameters
    ----------
    record : Record
        ``t`` (s, shifted), ``v`` (input units, the command in force over the
        interval ending at each row), ``y`` (degrees).
    time_shift : float
        Seconds added to the time column.

    """

    record: Record
    time_shift: float


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


def _is_number(cell: str) -> bool:
    try:
        float(cell)
    except ValueError:
        return False
    return True


def _table(text: str, delimiter: str, source: str) -> list[tuple[int, list[str]]]:
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


def _resolve(spec: str, header: list[str] | None, header_row: int, width: int, source: str,
             option: str) -> _Column:
    """Find the column a ``--time``/``--angle``/... value names."""
    if header is not None and spec in header:
        if header.count(spec) > 1:
            raise DataError(f'{source}: row {header_row}: {header.count(spec)} columns are '
                            f'named {spec!r} ({option}); choose one by 0-based index')
        index = header.index(spec)
        return _Column(index, f'{spec!r}')
    if spec.isdigit():
        index = int(spec)
        if index >= width:
            raise DataError(f'{source}: no column {index} ({option}): the file has {width} '
                            f'columns, 0 to {width - 1}')
        return _Column(index, f"'{header[index]}'" if header is not None else f'{index}')
    if header is None:
        raise DataError(f'{source}: no column {spec!r} ({option}): the file has no header row, '
                        'choose columns by 0-based index')
    names = ', '.join(header)
    raise DataError(f'{source}: row {header_row}: no column {spec!r} ({option}); '
                    f'columns: {names}')


def _values(rows: list[tuple[int, list[str]]], column: _Column, source: str) -> FloatArray:
    """Return the numbers of one column, naming the row and column of a bad cell."""
    cells = []
    for line, row in rows:
        if column.index >= len(row) or row[column.index] == '':
            raise DataError(f'{source}: row {line}, column {column.label}: empty '
                            f'(the row has {len(row)} cells)')
        cells.append(row[column.index])
    try:
        values = np.asarray(cells, dtype=np.float64)
    except ValueError:
        for (line, _), cell in zip(rows, cells):
            if not _is_number(cell):
                raise DataError(f'{source}: row {line}, column {column.label}: '
                                f'{cell!r} is not a number') from None
        raise
    bad = np.flatnonzero(~np.isfinite(values))
    if bad.size:
        k = int(bad[0])
        more = f' ({bad.size} such cells in the column)' if bad.size > 1 else ''
        raise DataError(f'{source}: row {rows[k][0]}, column {column.label}: {cells[k]!r} is not '
                        f'a finite number{more}')
    return values


def _check_time(t: FloatArray, rows: list[tuple[int, list[str]]], column: _Column,
                source: str) -> None:
    steps = np.diff(t)
    bad = np.flatnonzero(steps <= 0.0)
    if bad.size:
        k = int(bad[0])
        kind = 'repeats' if steps[k] == 0.0 else 'goes backwards from'
        more = f' ({bad.size} such rows in all)' if bad.size > 1 else ''
        raise DataError(f'{source}: row {rows[k + 1][0]}, column {column.label}: time '
                        f'{t[k + 1]:.9g} s {kind} {t[k]:.9g} s on row {rows[k][0]}{more}')


def record_from_log(t: FloatArray, y: FloatArray, command: FloatArray, *, joint: str,
                    source: str = '') -> CsvLog:
    """
    Turn logged rows into a record by the timing rule of the module docstring.

    Parameters
    ----------
    t : FloatArray
        Time of each row, s, strictly increasing (any start).
    y : FloatArray
        Angle of each row, degrees.
    command : FloatArray
        Command the logger applied at each row's time, input units.
    joint : str
        Joint name.
    source : str
        Where the rows came from, for messages.

    Returns
    -------
    CsvLog
        The record (``v_k`` = command of row ``k - 1``; ``v_0`` = command of row 0)
        and the time shift.

    """
    t = np.asarray(t, dtype=np.float64)
    if t.size < 2:
        raise DataError(f'{source or "log"}: {t.size} rows; a log needs at least 2')
    period = t[1] - t[0]
    # (t - t_0) is exact for nearby values, so large clock values lose nothing more.
    shifted = t if t[0] == period else (t - t[0]) + period
    record = Record(shifted, delayed(np.asarray(command, dtype=np.float64), 1), y,
                    joint=joint, source=source)
    return CsvLog(record, float(shifted[0] - t[0]))


def parse_csv_log(text: str, *, joint: str, time: str, angle: str, command: str,
                  command_negative: str | None = None, angle_unit: str = 'deg',
                  delimiter: str = ',', source: str = 'csv') -> CsvLog:
    """
    Parse the text of one CSV log.

    Parameters
    ----------
    text : str
        The file's content.
    joint : str
        Joint name for the record.
    time, angle, command : str
        Columns (header name or 0-based index) of the time (s), the angle and
        the command.
    command_negative : str or None
        Column subtracted from ``command`` (one-sided duty of the other
        direction's valve).
    angle_unit : str
        ``deg`` or ``rad``.
    delimiter : str
        Cell delimiter, one character (see :func:`delimiter_character`).
    source : str
        Name of the file, for messages.

    Returns
    -------
    CsvLog
        The record and the time shift.

    """
    if angle_unit not in ANGLE_UNITS:
        raise ConfigurationError(f"angle unit must be one of {', '.join(ANGLE_UNITS)}, "
                                 f'got {angle_unit!r}')
    if not joint:
        raise ConfigurationError('joint name must not be empty')
    rows = _table(text, delimiter_character(delimiter), source)
    if not rows:
        raise DataError(f'{source}: file is empty')
    first = rows[0][1]
    header = None if any(_is_number(cell) for cell in first) else first
    data = rows[1:] if header is not None else rows
    if len(data) < 2:
        plural = '' if len(data) == 1 else 's'
        raise DataError(f'{source}: {len(data)} data row{plural}; a log needs at least 2')
    width = len(first)
    specs = {'--time': time, '--angle': angle, '--command': command}
    if command_negative is not None:
        specs['--command-negative'] = command_negative
    columns = {option: _resolve(spec, header, rows[0][0], width, source, option)
               for option, spec in specs.items()}
    values = {option: _values(data, column, source) for option, column in columns.items()}
    _check_time(values['--time'], data, columns['--time'], source)
    y = values['--angle'] if angle_unit == 'deg' else np.degrees(values['--angle'])
    v = values['--command']
    if command_negative is not None:
        v = v - values['--command-negative']
    return record_from_log(values['--time'], y, v, joint=joint, source=source)


def read_csv_log(path: str | os.PathLike[str], *, joint: str, time: str, angle: str,
                 command: str, command_negative: str | None = None, angle_unit: str = 'deg',
                 delimiter: str = ',') -> CsvLog:
    """
    Read one CSV log file (UTF-8, with or without a byte-order mark).

    Parameters
    ----------
    path : str or PathLike
        The file.
    joint, time, angle, command, command_negative, angle_unit, delimiter
        As for :func:`parse_csv_log`.

    Returns
    -------
    CsvLog
        The record and the time shift.

    """
    source = Path(path)
    text = read_text(source, DataError, kind='a CSV file', byte_order_mark=True)
    return parse_csv_log(text, joint=joint, time=time, angle=angle, command=command,
                         command_negative=command_negative, angle_unit=angle_unit,
                         delimiter=delimiter, source=str(source))

"""A logger's text file as rows of cells: its encoding, its delimiter, its numbers."""

from __future__ import annotations

import codecs
import csv
from dataclasses import dataclass
import io
import os
from pathlib import Path

from hydro_sdp.core.arrays import FloatArray
from hydro_sdp.core.errors import ConfigurationError, DataError
from hydro_sdp.io.logs.table import first_time_fault
import numpy as np

#: Delimiters that are awkward to type in a shell, by name.
DELIMITER_NAMES = {'tab': '\t', '\\t': '\t', 'space': ' '}
#: Delimiters tried when none is named, in order of preference on a tie.
SNIFFED = (',', ';', '\t')
#: Lines read from each end of a file to choose its delimiter.
SNIFF_LINES = 400
#: Byte-order marks, the longer first (UTF-32 LE begins as UTF-16 LE does).
BYTE_ORDER_MARKS = ((codecs.BOM_UTF32_LE, 'utf-32'), (codecs.BOM_UTF32_BE, 'utf-32'),
                    (codecs.BOM_UTF8, 'utf-8-sig'), (codecs.BOM_UTF16_LE, 'utf-16'),
                    (codecs.BOM_UTF16_BE, 'utf-16'))
#: The single-byte reading of a file that is not UTF-8.
FALLBACK = 'latin-1'

#: Rows as ``(spreadsheet row number, stripped cells)``; a blank row has no cells.
Rows = list[tuple[int, list[str]]]


@dataclass(frozen=True)
class LogText:
    """
    A logger's file as text.

    Attributes
    ----------
    note : str
        Why it was read so, when it was not UTF-8 (empty otherwise).

    """

    text: str
    encoding: str
    note: str = ''


def check_encoding(name: str) -> str:
    """Return the codec name ``name`` stands for, or refuse it in one line."""
    try:
        return codecs.lookup(name).name
    except LookupError:
        raise ConfigurationError(f'--encoding: unknown encoding {name!r} (for example utf-8, '
                                 'utf-16, cp949, cp1252, latin-1)') from None


def _text(data: bytes, codec: str, note: str = '') -> LogText:
    # A mark the codec keeps (UTF-16-LE named for a file with a mark) is no character.
    return LogText(data.decode(codec).removeprefix('\ufeff'), codec, note)


def _row_of(data: bytes, at: int, encoding: str) -> int:
    return data[:at].decode(encoding, errors='replace').count('\n') + 1


def _utf16_without_mark(data: bytes) -> str | None:
    """Return ``utf-16-le`` or ``-be`` when every other byte is zero (ASCII text in UTF-16)."""
    half = len(data) // 2
    if half < 2:
        return None
    even, odd = data[0::2].count(0), data[1::2].count(0)
    if odd >= 0.6 * half and even <= 0.05 * half:
        return 'utf-16-le'
    if even >= 0.6 * half and odd <= 0.05 * half:
        return 'utf-16-be'
    return None


def decode_log(data: bytes, source: str, encoding: str | None = None) -> LogText:
    """
    Decode a logger's file (docs/interfaces.md section 4.4).

    ``data``: the file's bytes.
    ``encoding``: the encoding named by the user (strict: a byte it cannot read is refused).
    """
    if encoding is not None:
        codec = check_encoding(encoding)
        if codec == 'utf-8':
            codec = 'utf-8-sig'
        try:
            return _text(data, codec)
        except UnicodeDecodeError as failure:
            raise DataError(f'{source}: not {encoding} text (byte {failure.start}, row '
                            f'{_row_of(data, failure.start, codec)})') from None
    for mark, codec in BYTE_ORDER_MARKS:
        if data.startswith(mark):
            try:
                return _text(data, codec)
            except UnicodeDecodeError as failure:
                raise DataError(f'{source}: starts with a {codec} byte-order mark but is not '
                                f'{codec} text (byte {failure.start})') from None
    wide = _utf16_without_mark(data)
    if wide is not None:
        try:
            return _text(data, wide)
        except UnicodeDecodeError:
            pass
    try:
        return _text(data, 'utf-8')
    except UnicodeDecodeError as failure:
        row = _row_of(data, failure.start, 'utf-8')
        return _text(data, FALLBACK,
                     f'not UTF-8 (byte {failure.start}, row {row}): read one byte per '
                     'character (Latin-1); numbers and ASCII names read as they are, '
                     'name --encoding (cp949, cp1252...) for the rest')


def read_log_text(path: str | os.PathLike[str], encoding: str | None = None) -> LogText:
    """
    Read a logger's text file; each failure is one line naming the file.

    ``encoding``: its encoding, if the user named it.
    """
    source = Path(path)
    if source.is_dir():
        raise DataError(f'{source} is a directory, not a CSV file')
    try:
        data = source.read_bytes()
    except FileNotFoundError:
        raise DataError(f'{source}: no such file') from None
    except OSError as failure:
        raise DataError(f'{source}: cannot read: {failure}') from None
    return decode_log(data, str(source), encoding)


def delimiter_character(text: str) -> str:
    """
    Return the one-character delimiter that ``text`` names.

    ``text``: a single character, or ``tab`` (also a backslash and ``t``) or ``space``.
    """
    character = DELIMITER_NAMES.get(text, text)
    if len(character) != 1 or character in '"\r\n':
        raise ConfigurationError(f'delimiter must be one character (or tab, space), '
                                 f'got {text!r}')
    return character


def to_number(cell: str, decimal_comma: bool = False) -> float:
    """Return the number a cell reads as (a comma as the decimal point if so), or ValueError."""
    if decimal_comma and ',' in cell and '.' not in cell:
        cell = cell.replace(',', '.')
    return float(cell)


def is_number(cell: str, decimal_comma: bool = False) -> bool:
    """Whether a cell reads as a number."""
    try:
        to_number(cell, decimal_comma)
    except ValueError:
        return False
    return True


def numbers_row(cells: list[str], decimal_comma: bool = False) -> bool:
    """Whether a row is a sample: at least two filled cells, all numbers."""
    filled = [cell for cell in cells if cell != '']
    return len(filled) >= 2 and all(is_number(cell, decimal_comma) for cell in filled)


def _sample_row(line: str, delimiter: str) -> bool:
    cells = [cell.strip().strip('"').strip() for cell in line.split(delimiter)]
    if cells and cells[0].lower() == 'trace_values':
        cells = cells[1:]
    return numbers_row(cells, delimiter != ',')


def sniff_delimiter(text: str) -> str:
    """
    Return the delimiter of ``,``, ``;`` and tab that makes the most rows of numbers.

    ``text``: the file's content.
    """
    lines = text.splitlines()
    sample = lines if len(lines) <= 2 * SNIFF_LINES else \
        lines[:SNIFF_LINES] + lines[-SNIFF_LINES:]
    best, most = ',', 0
    for delimiter in SNIFFED:
        count = sum(_sample_row(line, delimiter) for line in sample)
        if count > most:
            best, most = delimiter, count
    return best


def read_rows(text: str, delimiter: str, source: str) -> Rows:
    """
    Split text into rows of stripped cells, blank rows kept empty, trailing empty cells dropped.

    ``text``: the file's content.
    """
    reader = csv.reader(io.StringIO(text, newline=''), delimiter=delimiter)
    rows = []
    try:
        for cells in reader:
            stripped = [cell.strip() for cell in cells]
            while stripped and stripped[-1] == '':
                stripped.pop()
            rows.append((reader.line_num, stripped))
    except csv.Error as error:
        raise DataError(f'{source}: row {reader.line_num}: not CSV ({error})') from None
    return rows


def column_values(data: Rows, index: int, label: str, source: str,
                  decimal_comma: bool = False) -> FloatArray:
    """
    Return the numbers of one column of sample rows, naming the row and column of a bad cell.

    ``data``: the sample rows.
    ``decimal_comma``: whether a comma in a number is its decimal point.
    Returns: one finite number per row.
    """
    cells = []
    for line, row in data:
        if index >= len(row) or row[index] == '':
            raise DataError(f'{source}: row {line}, {label}: empty (the row has {len(row)} '
                            'cells)')
        cells.append(row[index])
    try:
        values = np.array([to_number(cell, decimal_comma) for cell in cells], dtype=np.float64)
    except ValueError:
        for (line, _), cell in zip(data, cells):
            if not is_number(cell, decimal_comma):
                raise DataError(f'{source}: row {line}, {label}: {cell!r} is not a '
                                'number') from None
        raise
    bad = np.flatnonzero(~np.isfinite(values))
    if bad.size:
        k = int(bad[0])
        more = f' ({bad.size} such cells in the column)' if bad.size > 1 else ''
        raise DataError(f'{source}: row {data[k][0]}, {label}: {cells[k]!r} is not a finite '
                        f'number{more}')
    return values


def check_time_column(t: FloatArray, data: Rows, label: str, source: str) -> None:
    """Refuse a time column that repeats or goes backwards, naming its rows."""
    fault = first_time_fault(t)
    if fault is not None:
        k = fault.index
        more = f' ({fault.count} such rows in all)' if fault.count > 1 else ''
        raise DataError(f'{source}: row {data[k + 1][0]}, {label}: time {t[k + 1]:.9g} s '
                        f'{fault.kind} {t[k]:.9g} s on row {data[k][0]}{more}')

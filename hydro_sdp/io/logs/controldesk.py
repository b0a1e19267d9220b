"""dSPACE ControlDesk recorder exports (CSV): sections of rows keyed by their first cell."""

from __future__ import annotations

from dataclasses import dataclass
import re

from hydro_sdp.core.arrays import FloatArray
from hydro_sdp.core.errors import DataError
from hydro_sdp.io.logs.table import Channel
from hydro_sdp.io.logs.text_rows import check_time_column, column_values, Rows

#: The key of the row where the samples start.
DATA_KEY = 'trace_values'
#: A Simulink block port, which names no signal.
PORT = re.compile(r'(in|out)(port)?\d*\Z', re.IGNORECASE)
#: The name of every section's time column.
TIME_NAME = 'time'


def is_controldesk(rows: Rows) -> bool:
    """Whether rows are a ControlDesk export: one of them is keyed ``trace_values``."""
    return any(cells and cells[0].lower() == DATA_KEY for _, cells in rows)


def signal_name(trace: str, path: str) -> str:
    """
    Return a column's name as a user reads it (docs/interfaces.md section 4.4).

    ``trace``: its trace name (may be empty).
    ``path``: its block path (may be empty).
    """
    if trace and not PORT.match(trace):
        return trace
    for element in reversed([part.strip() for part in path.split('/')]):
        if element and element != trace and not PORT.match(element):
            return element
    return trace


@dataclass(frozen=True)
class _Section:
    number: int
    keyed: dict[str, list[str]]
    data: Rows


@dataclass(frozen=True)
class _TraceColumn:
    section: _Section
    index: int
    name: str
    path: str

    @property
    def label(self) -> str:
        if self.index == 1:
            return 'the time column'
        return f'signal {self.name!r}' if self.name else f'column {self.index}'


def _sections(rows: Rows) -> list[_Section]:
    """Split the rows into sections: keyed rows, then the samples from ``trace_values`` on."""
    sections: list[_Section] = []
    keyed: dict[str, list[str]] = {}
    data: Rows | None = None
    for line, cells in rows:
        key = cells[0].lower() if cells else ''
        if data is not None:
            if cells and key == '':
                data.append((line, cells))
                continue
            sections.append(_Section(len(sections) + 1, keyed, data))
            keyed, data = {}, None
        if key == DATA_KEY:
            data = [(line, cells)]
        elif key:
            keyed[key] = cells
    if data is not None:
        sections.append(_Section(len(sections) + 1, keyed, data))
    return sections


def _cell(cells: list[str], index: int) -> str:
    return cells[index] if index < len(cells) else ''


def _columns(section: _Section) -> list[_TraceColumn]:
    names = section.keyed.get('trace_names', [])
    paths = section.keyed.get('path', [])
    width = max([len(cells) for cells in section.keyed.values()]
                + [len(cells) for _, cells in section.data])
    columns = [_TraceColumn(section, 1, TIME_NAME, _cell(paths, 1))]
    for index in range(2, width):
        trace, path = _cell(names, index), _cell(paths, index)
        columns.append(_TraceColumn(section, index, signal_name(trace, path), path))
    return columns


class ControlDeskTable:
    """
    The signals of a ControlDesk export, each timed by its section's time column.

    ``rows``: the file's rows (:func:`.text_rows.read_rows`).
    ``time``: time column (default: each section's own); a signal names a time for the signals of
    its section.
    ``decimal_comma``: whether a comma in a number is its decimal point.
    ``notes``: what the user should know of how the file was read.
    """

    def __init__(self, rows: Rows, time: str | None, *, source: str = 'csv',
                 time_role: str = '--time', decimal_comma: bool = False,
                 notes: tuple[str, ...] = ()) -> None:
        self.source = source
        self.decimal_comma = decimal_comma
        self.sections = _sections(rows)
        self.columns = [column for section in self.sections for column in _columns(section)]
        self.aliases: dict[str, list[_TraceColumn]] = {}
        for column in self.columns:
            for alias in names_of(column):
                found = self.aliases.setdefault(alias, [])
                if column not in found:
                    found.append(column)
        signals = sum(column.index > 1 for column in self.columns)
        plural = '' if len(self.sections) == 1 else 's'
        self.notes = notes + (f'read as a dSPACE ControlDesk export: {len(self.sections)} '
                              f'section{plural}, {signals} signals',)
        self._times: dict[int, FloatArray] = {}
        self.time_column: _TraceColumn | None = None
        if time is not None:
            found = self.aliases.get(time, [])
            if not found or any(column.index != 1 for column in found):
                column = self._resolve(time, time_role)
                self.time_column = None if column.index == 1 else column

    def channel(self, name: str, role: str) -> Channel:
        """Return signal ``name`` (its name, trace name, path or index), timed by its section."""
        column = self._resolve(name, role)
        values = self._values(column)
        timing = self.time_column
        if timing is not None and timing.section is not column.section:
            raise DataError(f'{self.source}: {column.label} ({role}) is in section '
                            f'{column.section.number}, the time named in section '
                            f'{timing.section.number}; leave out the time to use each '
                            "section's own")
        t = self._time(column.section) if timing is None else self._values(timing)
        if timing is not None:
            check_time_column(t, timing.section.data, self._label(timing), self.source)
        return Channel(name, t, values, self._label(column))

    def _time(self, section: _Section) -> FloatArray:
        if section.number not in self._times:
            column = _TraceColumn(section, 1, TIME_NAME, '')
            t = self._values(column)
            check_time_column(t, section.data, self._label(column), self.source)
            self._times[section.number] = t
        return self._times[section.number]

    def _label(self, column: _TraceColumn) -> str:
        where = '' if len(self.sections) == 1 else f' of section {column.section.number}'
        return column.label + where

    def _values(self, column: _TraceColumn) -> FloatArray:
        return column_values(column.section.data, column.index, self._label(column),
                             self.source, self.decimal_comma)

    def _resolve(self, spec: str, option: str) -> _TraceColumn:
        """Find the column a ``--time``/``--angle``/... value names."""
        source = self.source
        found = self.aliases.get(spec, [])
        if len(found) == 1:
            return found[0]
        if found:
            listed = ', '.join(f'{column.path or column.name} (section {column.section.number}, '
                               f'column {column.index})' for column in found)
            raise DataError(f'{source}: {len(found)} columns answer to {spec!r} ({option}): '
                            f'{listed}; name one by its path')
        if spec.isdigit():
            first = [column for column in self.columns if column.section.number == 1]
            index = int(spec)
            if index == 0:
                raise DataError(f'{source}: column 0 ({option}) holds the row keys of a '
                                'ControlDesk export; its time is column 1')
            if index > first[-1].index:
                raise DataError(f'{source}: no column {index} ({option}): the first section '
                                f'has columns 1 to {first[-1].index}')
            return first[index - 1]
        names = ', '.join(column.name for column in self.columns if column.index > 1
                          and column.name)
        notes = ''.join(f'; {note}' for note in self.notes if 'ControlDesk' not in note)
        raise DataError(f'{source}: no signal {spec!r} ({option}); signals: {names}{notes}')


def names_of(column: _TraceColumn) -> list[str]:
    """Return the names a column answers to: its name, its trace name, its whole path."""
    trace = _cell(column.section.keyed.get('trace_names', []), column.index)
    names = [column.name, trace, column.path]
    if column.path and trace and column.path.rsplit('/', 1)[-1].strip() != trace:
        names.append(f'{column.path}/{trace}')
    return [name for name in dict.fromkeys(names) if name]

"""A logger's file as a machine's records: every joint, its command, and more signals."""

from __future__ import annotations

from contextlib import closing, contextmanager
from dataclasses import dataclass
import os
from pathlib import Path
from typing import Iterator, Mapping

from hydro_sdp.core.arrays import FloatArray
from hydro_sdp.core.errors import DataError
from hydro_sdp.core.model.records import Record
from hydro_sdp.io.logs.csv_table import text_table
from hydro_sdp.io.logs.mat_table import MAT_SUFFIXES, MatTable
from hydro_sdp.io.logs.mdf_table import MDF_SUFFIXES, MdfTable
from hydro_sdp.io.logs.signals_file import MachineSpec
from hydro_sdp.io.logs.table import check_channel, held_at, LogTable, nanoseconds
from hydro_sdp.io.logs.text_rows import read_log_text
import numpy as np


@dataclass(frozen=True, eq=False)
class MachineLog:
    """
    One logger's file read as records.

    Attributes
    ----------
    records : tuple[Record, ...]
        One per joint, in the signals file's order, sharing their time stamps: ``t`` (s, shifted),
        ``v`` (the command in force over the interval ending at each sample; zero for a joint
        without a command), ``y`` (degrees).
    signals : Mapping[str, FloatArray]
        Each signal's value at each sample, by topic.
    time_shift : float
        Seconds added to the file's time.
    notes : tuple[str, ...]
        How the file was read, when the user should know (its layout, its encoding).

    """

    records: tuple[Record, ...]
    commanded: tuple[str, ...]
    signals: Mapping[str, FloatArray]
    time_shift: float
    notes: tuple[str, ...] = ()

    @property
    def samples(self) -> int:
        """Return the number of samples."""
        return len(self.records[0])


def log_kind(path: str | os.PathLike[str]) -> str:
    """Return ``mdf``, ``mat`` or ``csv``: how a logger's file is read, by its name."""
    suffix = Path(path).suffix.lower()
    if suffix in MDF_SUFFIXES:
        return 'mdf'
    if suffix in MAT_SUFFIXES:
        return 'mat'
    return 'csv'


@contextmanager
def open_table(path: str | os.PathLike[str], time: str | None, *, time_role: str = '--time',
               header_row: int | None = None, delimiter: str | None = None,
               encoding: str | None = None) -> Iterator[LogTable]:
    """
    Open a logger's file by its kind (:func:`log_kind`); closed on leaving.

    ``time``: time column or variable (optional for MDF4).
    ``header_row``: CSV names row (spreadsheet number).
    ``delimiter``: CSV cell delimiter (default: sniffed).
    ``encoding``: CSV text encoding (default: detected, :mod:`.text_rows`).
    Yields: the file's channels.
    """
    kind = log_kind(path)
    if kind == 'mdf':
        with closing(MdfTable(path, time, time_role=time_role)) as mdf:
            yield mdf
    elif kind == 'mat':
        with closing(MatTable(path, time, time_role=time_role)) as mat:
            yield mat
    else:
        text = read_log_text(path, encoding)
        yield text_table(text.text, time, delimiter=delimiter, source=str(path),
                         header_row=header_row, time_role=time_role,
                         notes=(text.note,) if text.note else ())


def _role(spec: MachineSpec, joint: str, key: str) -> str:
    if spec.source == 'command line':
        return '--' + key.replace('_', '-')
    return f'joints.{joint}.{key}'


def machine_log(table: LogTable, spec: MachineSpec) -> MachineLog:
    """
    Read a machine's joints and signals from an open logger's file.

    ``spec``: which channels are which (the signals file, or the single-joint options).
    Returns: the records and signals on the first joint's angle samples.
    """
    source = table.source
    names = list(spec.joints)
    first = spec.joints[names[0]]
    base = check_channel(source, table.channel(first.angle, _role(spec, names[0], 'angle')))
    if base.t.size < 2:
        raise DataError(f'{source}: {base.label}: {base.t.size} sample; a log needs at least 2')
    origin = float(base.t[0])
    samples = nanoseconds(base.t, origin)
    records = []
    for name in names:
        channels = spec.joints[name]
        angle = base if name == names[0] else check_channel(
            source, table.channel(channels.angle, _role(spec, name, 'angle')))
        y = held_at(samples, angle, origin, command=False)
        if channels.angle_unit == 'rad':
            y = np.degrees(y)
        v = np.zeros(samples.size)
        for key, sign in (('command', 1.0), ('command_negative', -1.0)):
            column = getattr(channels, key)
            if column is not None:
                command = check_channel(source, table.channel(column, _role(spec, name, key)))
                v = v + sign * held_at(samples, command, origin, command=True)
        records.append((name, v, y))
    signals = {}
    for topic, column in spec.signals.items():
        role = '--load' if spec.source == 'command line' else f'signals.{topic.lstrip("/")}'
        signal = check_channel(source, table.channel(column, role))
        signals[topic] = held_at(samples, signal, origin, command=False)
    period = float(samples[1] - samples[0]) * 1e-9
    t = samples * 1e-9 + period
    return MachineLog(tuple(Record(t, v, y, joint=name, source=source)
                            for name, v, y in records),
                      tuple(name for name in names if spec.joints[name].command is not None),
                      signals, float(t[0] - origin), tuple(getattr(table, 'notes', ())))


def read_machine_log(path: str | os.PathLike[str], spec: MachineSpec, *,
                     header_row: int | None = None, delimiter: str | None = None,
                     encoding: str | None = None) -> MachineLog:
    """Read a logger's file (CSV, MDF4 or MATLAB) as a machine's records."""
    role = '--time' if spec.source == 'command line' else 'time'
    with open_table(path, spec.time, time_role=role, header_row=header_row,
                    delimiter=delimiter, encoding=encoding) as table:
        return machine_log(table, spec)

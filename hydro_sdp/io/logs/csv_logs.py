"""CSV logs of one joint, read as records ready to be written as bags (methods 3.4)."""

from __future__ import annotations

from dataclasses import dataclass
import os
from pathlib import Path

from hydro_sdp.core.arrays import FloatArray
from hydro_sdp.core.errors import DataError
from hydro_sdp.core.model.records import Record
from hydro_sdp.core.model.timing import delayed
from hydro_sdp.io.logs.csv_table import text_table
from hydro_sdp.io.logs.machine_log import machine_log
from hydro_sdp.io.logs.signals_file import single_joint_spec
from hydro_sdp.io.logs.text_rows import read_log_text
import numpy as np


@dataclass(frozen=True, eq=False)
class CsvLog:
    """
    One CSV log as a record.

    Attributes
    ----------
    record : Record
        ``t`` (s, shifted), ``v`` (input units, the command in force over the interval ending at
        each row), ``y`` (degrees).

    """

    record: Record
    time_shift: float


def record_from_log(t: FloatArray, y: FloatArray, command: FloatArray, *, joint: str,
                    source: str = '') -> CsvLog:
    """
    Turn logged rows into a record by the timing rule of methods 3.4.

    ``t``: time of each row, s, strictly increasing (any start).
    ``y``: angle of each row, degrees.
    ``command``: command the logger applied at each row's time, input units.
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
                  delimiter: str | None = None, source: str = 'csv',
                  header_row: int | None = None) -> CsvLog:
    """Parse the text of one CSV log."""
    spec = single_joint_spec(joint, angle, command, time=time,
                             command_negative=command_negative, angle_unit=angle_unit)
    table = text_table(text, time, delimiter=delimiter, source=source, header_row=header_row)
    log = machine_log(table, spec)
    return CsvLog(log.records[0], log.time_shift)


def read_csv_log(path: str | os.PathLike[str], *, joint: str, time: str, angle: str,
                 command: str, command_negative: str | None = None, angle_unit: str = 'deg',
                 delimiter: str | None = None, header_row: int | None = None,
                 encoding: str | None = None) -> CsvLog:
    """Read one CSV log file (any common encoding, :mod:`.text_rows`)."""
    source = Path(path)
    text = read_log_text(source, encoding).text
    return parse_csv_log(text, joint=joint, time=time, angle=angle, command=command,
                         command_negative=command_negative, angle_unit=angle_unit,
                         delimiter=delimiter, source=str(source), header_row=header_row)

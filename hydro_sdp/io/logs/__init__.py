"""Loggers' files: CSV, ASAM MDF4 and MATLAB ``.mat``, read as a machine's records."""

from hydro_sdp.io.logs.csv_logs import CsvLog, parse_csv_log, read_csv_log, record_from_log
from hydro_sdp.io.logs.machine_log import log_kind, MachineLog, open_table, read_machine_log
from hydro_sdp.io.logs.signals_file import (
    ANGLE_UNITS, JointChannels, load_signals, MachineSpec, single_joint_spec)
from hydro_sdp.io.logs.table import Channel
from hydro_sdp.io.logs.text_rows import delimiter_character, read_log_text

__all__ = ['ANGLE_UNITS', 'Channel', 'CsvLog', 'JointChannels', 'MachineLog', 'MachineSpec',
           'delimiter_character', 'load_signals', 'log_kind', 'open_table', 'parse_csv_log',
           'read_csv_log', 'read_log_text', 'read_machine_log', 'record_from_log',
           'single_joint_spec']

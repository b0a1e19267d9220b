"""
Loggers' files: CSV, ASAM MDF4 and MATLAB ``.mat``, read as a machine's records.

Each format gives channels with their own time (:mod:`.table`): CSV columns
(:mod:`.csv_table`; a dSPACE ControlDesk export by its own layout, :mod:`.controldesk`;
the text in any common encoding, :mod:`.text_rows`), MDF4 channels on their groups' time bases
(:mod:`.mdf_table`), MATLAB variables (:mod:`.mat_table`). The signals file
(:mod:`.signals_file`) says which channels are which joint's angle and command
and which are more signals; :mod:`.machine_log` puts them all on the first
joint's angle samples. :mod:`.csv_logs` is the one-joint CSV reading the
``import`` options have always done.

"""

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

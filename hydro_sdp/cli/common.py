"""What every ``hydro-sdp`` command shares: options, output and exit codes."""

from __future__ import annotations

import argparse
from dataclasses import dataclass, field
import math
from typing import Any, Union

from hydro_sdp.core.errors import ConfigurationError
from hydro_sdp.core.model.timing import SamplePeriod
import numpy as np

#: What ``json`` writes: null, booleans, numbers, text, and lists and objects of them.
Json = Union[None, bool, int, float, str, list['Json'], dict[str, 'Json']]
#: A command's ``--json`` object as the command builds it: any value :func:`to_json`
#: turns into JSON (numpy numbers and arrays, tuples and paths too), keys the command
#: may read back for its text report.
Payload = dict[str, Any]


@dataclass
class Outcome:
    """
    Result of one command.

    Parameters
    ----------
    payload : Payload
        The ``--json`` object.
    lines : list of str
        Human-readable report, one entry per line.

    """

    payload: Payload
    lines: list[str] = field(default_factory=list)


def _parse_number(text: str) -> float:
    try:
        return float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f'expected a number, got {text!r}') from None


def json_number(value: float) -> float | None:
    """Return ``value`` for a ``--json`` object, or None (JSON null) if it is not finite."""
    return value if math.isfinite(value) else None


def positive_float(text: str) -> float:
    """Argparse type: a finite number > 0."""
    value = _parse_number(text)
    if not (math.isfinite(value) and value > 0.0):
        raise argparse.ArgumentTypeError(f'must be a positive number, got {text!r}')
    return value


def period_seconds(text: str) -> SamplePeriod:
    """Argparse type: a sample or control period, s (checked as :class:`SamplePeriod`)."""
    try:
        return SamplePeriod(_parse_number(text))
    except ConfigurationError:
        raise argparse.ArgumentTypeError(
            f'must be a positive number of seconds, got {text!r}') from None


def non_negative_float(text: str) -> float:
    """Argparse type: a finite number >= 0."""
    value = _parse_number(text)
    if not (math.isfinite(value) and value >= 0.0):
        raise argparse.ArgumentTypeError(f'must be a number >= 0, got {text!r}')
    return value


def row_number(text: str) -> int:
    """Argparse type: a row number from 1, as a spreadsheet numbers rows."""
    if not text.isdigit() or int(text) < 1:
        raise argparse.ArgumentTypeError(f'must be a row number from 1, got {text!r}')
    return int(text)


def finite_float(text: str) -> float:
    """Argparse type: any finite number."""
    value = _parse_number(text)
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f'must be finite, got {text!r}')
    return value


def to_json(value: object) -> Json:
    """Convert numpy scalars, arrays, tuples and paths into JSON-ready values."""
    if isinstance(value, dict):
        return {str(key): to_json(item) for key, item in value.items()}
    if isinstance(value, (list, tuple)):
        return [to_json(item) for item in value]
    if isinstance(value, np.ndarray):
        return [to_json(item) for item in value.tolist()]
    if isinstance(value, (np.floating, float)):
        number = float(value)
        return number if math.isfinite(number) else None
    if isinstance(value, (np.integer,)):
        return int(value)
    if isinstance(value, (str, int, bool)) or value is None:
        return value
    return str(value)


def table(rows: list[list[str]], header: list[str]) -> list[str]:
    """Format rows as a plain-text table with aligned columns."""
    widths = [max(len(str(row[i])) for row in [header] + rows) for i in range(len(header))]
    lines = ['  '.join(str(cell).ljust(width) for cell, width in zip(header, widths)).rstrip(),
             '  '.join('-' * width for width in widths)]
    lines += ['  '.join(str(cell).ljust(width) for cell, width in zip(row, widths)).rstrip()
              for row in rows]
    return lines


def read_records(bags: list[str], joint: str | None, command_topic: str | None,
                 label: str = 'reading bags', *, preferred_topic: str | None = None,
                 load_topic: str | None = None, others: bool = False) -> list:
    """
    Read one joint's record from each bag, cut at gaps in its time stamps, with a progress bar.

    ``joint``: joint name (default: the only joint of each bag).
    ``command_topic``: command topic (default: ``preferred_topic`` where the bag has it, else the
    only ``valve_command`` topic).
    ``label``: progress bar label.
    ``preferred_topic``: topic remembered by a model file (its ``command_topic``).
    ``load_topic``: Float64 topic of a measured load, carried as the records' ``load``.
    ``others``: carry the other joints' angles of the JointState as the records' ``others`` (what
    ``flow_sharing`` needs).
    Returns: one per bag, or several where a stalled recording left a hole
    (:func:`hydro_sdp.core.model.records.split_at_gaps`).
    """
    return read_records_and_topic(bags, joint, command_topic, label,
                                  preferred_topic=preferred_topic, load_topic=load_topic,
                                  others=others)[0]


def pieces_note(bags: list[str], records: list) -> list[str]:
    """Return the line saying the bags were cut at gaps into more records, if they were."""
    if len(records) == len(bags):
        return []
    return [f'{len(bags)} bags read as {len(records)} pieces (cut at gaps in the time stamps)']


def read_records_and_topic(bags: list[str], joint: str | None, command_topic: str | None,
                           label: str = 'reading bags', *,
                           preferred_topic: str | None = None, load_topic: str | None = None,
                           others: bool = False) -> tuple[list, str | None]:
    """
    Read records as :func:`read_records` does, and name the command topic they came from.

    ``joint``: joint name (default: the only joint of each bag).
    ``command_topic``: command topic asked for by the user.
    ``label``: progress bar label.
    ``preferred_topic``: topic used when ``command_topic`` is None and the bag has it.
    Returns: ``(records, topic)``: the topic every bag was read from, or ``None`` when the bags
    used different topics.
    """
    from hydro_sdp.cli.progress import ProgressBar

    records: list = []
    topics: set[str] = set()
    with ProgressBar(label, len(bags)) as bar:
        for done, bag in enumerate(bags, start=1):
            pieces, topic = read_bag_records(bag, joint, command_topic,
                                             preferred_topic=preferred_topic,
                                             load_topic=load_topic, others=others)
            records.extend(pieces)
            topics.add(topic)
            bar.update(done)
    return records, (topics.pop() if len(topics) == 1 else None)


def read_bag_records(bag: str, joint: str | None, command_topic: str | None, *,
                     preferred_topic: str | None = None, load_topic: str | None = None,
                     others: bool = False) -> tuple[list, str]:
    """
    Read one joint's record from one bag, cut at gaps in its time stamps.

    Returns: ``(pieces, topic)``: the record, or its pieces where a stalled recording left a hole,
    and the command topic read.
    """
    from hydro_sdp.bags import read_bag
    from hydro_sdp.core.model.records import split_at_gaps

    data = read_bag(bag)
    name = data.choose_joint(joint)
    asked = command_topic
    if asked is None and preferred_topic is not None and preferred_topic in data.floats:
        asked = preferred_topic
    topic = data.command_topic(name, asked)
    record = data.record(name, topic, load_topic=load_topic, others=others)
    return list(split_at_gaps(record).records), topic


def add_bag_options(parser: argparse.ArgumentParser) -> None:
    """Add ``--joint`` and ``--command-topic`` (docs/interfaces.md section 2)."""
    parser.add_argument('--joint', help='joint name in JointState (default: the only one)')
    parser.add_argument('--command-topic',
                        help='Float64 command topic (default: the only one ending in '
                             'valve_command)')


def add_text_options(parser: argparse.ArgumentParser | argparse._ArgumentGroup) -> None:
    """Add the options of CSV files: ``--header-row``, ``--delimiter``, ``--encoding``."""
    parser.add_argument('--header-row', type=row_number, metavar='N',
                        help='CSV: the row holding the column names, numbered as a spreadsheet '
                             'does (default: found above the first row of numbers)')
    parser.add_argument('--delimiter', metavar='D',
                        help='CSV cell delimiter: one character, or tab or space (default: the '
                             'one of , ; tab that makes rows of numbers)')
    parser.add_argument('--encoding', metavar='NAME',
                        help='CSV text encoding, e.g. cp949, cp1252, utf-16 (default: a '
                             'byte-order mark, else UTF-8, else one byte per character)')

"""Reading the messages of sqlite3 storage files in bulk, one query per topic."""

from __future__ import annotations

import gc
from pathlib import Path
import sqlite3
from typing import Sequence, TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from rosbags.interfaces import Connection
    from rosbags.rosbag2 import Reader

#: Rows of one topic: receive times (ns) and raw CDR messages, in reading order.
TopicRows = tuple[list[int], list[bytes]]


def matches(wanted: Connection, stored: Connection) -> bool:
    """Whether a storage file's connection feeds a wanted connection (rosbags' rule)."""
    return bool(wanted.topic == stored.topic and wanted.msgtype == stored.msgtype and
                wanted.ext == stored.ext and digests_agree(wanted.digest, stored.digest))


def digests_agree(wanted: str, stored: str) -> bool:
    """Return whether two type hashes agree, as rosbags judges them (an empty one agrees)."""
    return not wanted or not stored or wanted == stored


def open_immutable(path: Path) -> sqlite3.Connection:
    """Open a storage file read-only and unlocked (a finished bag does not change)."""
    return sqlite3.connect(f'{path.resolve().as_uri()}?immutable=1', uri=True)


def _storages(reader: Reader) -> list[tuple[Path, list[Connection]]] | None:
    """Return each sqlite3 storage file of an open reader with its connections, or None."""
    if reader.compression_mode:
        return None
    storage = reader.storage
    # A bag folder's reader holds one reader per storage file; a storage file is its own.
    parts = getattr(storage, 'storages', [storage])
    out = []
    for part in parts:
        path, connections = getattr(part, 'path', None), getattr(part, 'connections', None)
        if not (isinstance(path, Path) and path.suffix == '.db3' and
                isinstance(connections, list)):
            return None
        out.append((path, connections))
    return out


def topic_rows(connection: sqlite3.Connection, topic_ids: Sequence[int]) -> TopicRows:
    """
    Fetch the messages of some topic ids of one storage file, ordered by receive time.

    Parameters
    ----------
    connection : sqlite3.Connection
        The storage file, open.
    topic_ids : sequence of int
        Ids in its ``topics`` table (of one topic name).

    Returns
    -------
    tuple
        Receive times (ns) and raw messages, by time, ties in storage order.

    """
    marks = ', '.join('?' * len(topic_ids))
    # A row is a new tuple: the cyclic collector would walk them all again and again
    # while they pile up, and tuples of numbers and bytes hold no cycles.
    collecting = gc.isenabled()
    gc.disable()
    try:
        rows = connection.execute(
            f'SELECT timestamp, data FROM messages WHERE topic_id IN ({marks})',
            tuple(topic_ids)).fetchall()
        stamps = [row[0] for row in rows]
        raws = [row[1] for row in rows]
        del rows
    finally:
        if collecting:
            gc.enable()
    times = np.fromiter(stamps, dtype=np.int64, count=len(stamps))
    if times.size > 1 and bool(np.any(times[1:] < times[:-1])):
        order = np.argsort(times, kind='stable').tolist()
        stamps = [stamps[i] for i in order]
        raws = [raws[i] for i in order]
    return stamps, raws


def read_rows(reader: Reader, wanted: Sequence[Connection]) -> list[dict[str, TopicRows]] | None:
    """
    Read the messages of the wanted connections of an open sqlite3 bag, a query per topic.

    Parameters
    ----------
    reader : rosbags.rosbag2.Reader
        The bag, open (rosbags has checked its metadata and storage files).
    wanted : sequence of rosbags Connection
        Connections of that reader whose messages to read.

    Returns
    -------
    list of dict or None
        Per storage file, the rows of each topic that has any; None when the bag
        is not plain sqlite3 storage.

    """
    storages = _storages(reader)
    if storages is None:
        return None
    files = []
    for path, connections in storages:
        by_topic: dict[str, list[int]] = {}
        for stored in connections:
            if any(matches(w, stored) for w in wanted):
                by_topic.setdefault(stored.topic, []).append(int(stored.id))
        database = open_immutable(path)
        try:
            files.append({topic: topic_rows(database, ids) for topic, ids in by_topic.items()})
        finally:
            database.close()
    return files

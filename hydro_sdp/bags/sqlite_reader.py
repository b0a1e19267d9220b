"""
sqlite3 storage read a query per topic: 2x faster than rosbags' Reader (bench/bench_bags.py).

rosbags counts every topic's messages when it opens a storage file and hands messages back one
by one; this reader matches topics by rosbags' rules and fetches each topic's rows at once.
What it does not take (mcap, compression, metadata it cannot judge, damaged files) it leaves
to rosbags by returning None.
"""

from __future__ import annotations

from dataclasses import dataclass
import gc
from pathlib import Path, PurePath
import sqlite3
from typing import Any, Callable, Sequence

import numpy as np
import yaml

#: Rows of one topic: receive times (ns) and raw CDR messages, in reading order.
TopicRows = tuple[list[int], list[bytes]]


@dataclass(frozen=True)
class SqliteBag:
    """
    The topics and kept messages of an sqlite3 bag folder or storage file.

    Parameters
    ----------
    declared : int
        Messages the metadata counts (the storage file's own count for a bare file).
    topics : list of tuple[str, str]
        ``(topic, msgtype)`` of every topic, in the bag's order.
    files : list of dict
        Per storage file, the rows of each kept topic that has any.

    """

    declared: int
    topics: list[tuple[str, str]]
    files: list[dict[str, TopicRows]]


def _qos_agree(wanted: Any, stored: Any) -> bool:
    """Whether metadata and storage QoS are the same profiles, as rosbags judges them."""
    if wanted == stored or (not wanted and not stored):
        return True
    # Texts that differ may still parse to the same profiles (Jazzy writes a YAML list).
    from rosbags.rosbag2.metadata import parse_qos

    return bool(parse_qos(wanted) == parse_qos(stored))


def _metadata(folder: Path) -> dict[str, Any] | None:
    # Walked on trust: read_sqlite turns any key or type that is not there into None.
    loader = getattr(yaml, 'CSafeLoader', yaml.SafeLoader)
    info = yaml.load((folder / 'metadata.yaml').read_text(), Loader=loader)
    info = info['rosbag2_bagfile_information']
    mode = str(info.get('compression_mode') or 'none').lower()
    if not (isinstance(info['version'], int) and info['version'] <= 9) or \
            info['storage_identifier'] != 'sqlite3' or mode != 'none':
        return None
    for key in ('duration', 'starting_time'):   # rosbags refuses metadata without them
        info[key]['nanoseconds' if key == 'duration' else 'nanoseconds_since_epoch']
    return dict(info)


def _open_immutable(path: Path) -> sqlite3.Connection:
    # A finished bag does not change: read-only and unlocked, as rosbags opens it.
    return sqlite3.connect(f'{path.resolve().as_uri()}?immutable=1', uri=True)


def _storage_topics(database: sqlite3.Connection) -> list[tuple[int, str, str, str, str, str]]:
    """Return ``(id, name, type, serialisation, qos, hash)`` of a storage file's topics."""
    tables = {row[0] for row in database.execute(
        "SELECT name FROM sqlite_master WHERE type = 'table'")}
    columns = {row[1] for row in database.execute('PRAGMA table_info(topics)')}
    if not {'messages', 'topics'} <= tables:
        raise LookupError('not a storage file')
    schema = database.execute('SELECT schema_version FROM schema').fetchone()[0] \
        if 'schema' in tables else 2
    if schema >= 4 and 'message_definitions' not in tables:
        raise LookupError('schema 4 without message definitions')
    qos = 'offered_qos_profiles' if 'offered_qos_profiles' in columns else "''"
    digest = 'type_description_hash' if schema >= 4 else "''"
    return database.execute(f'SELECT id, name, type, serialization_format, {qos}, {digest} '
                            'FROM topics ORDER BY id').fetchall()


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


def _read_file(path: Path, keep: Callable[[str], bool]) -> SqliteBag:
    """Read a bare storage file: its own topics, every message counted."""
    database = _open_immutable(path)
    try:
        topics = _storage_topics(database)
        ids: dict[str, list[int]] = {}
        for topic_id, name, msgtype, *_ in topics:
            if keep(msgtype):
                ids.setdefault(name, []).append(int(topic_id))
        rows = {name: topic_rows(database, found) for name, found in ids.items()}
        declared = database.execute('SELECT count(*) FROM messages').fetchone()[0]
    finally:
        database.close()
    return SqliteBag(int(declared), [(name, msgtype) for _, name, msgtype, *_ in topics], [rows])


def _read_folder(folder: Path, keep: Callable[[str], bool]) -> SqliteBag | None:
    """Read a bag folder: the metadata's topics, fed by the storage topics that match them."""
    info = _metadata(folder)
    if info is None:
        return None
    connections = []
    for entry in info['topics_with_message_count']:
        meta = entry['topic_metadata']
        if meta['serialization_format'] != 'cdr':
            return None                 # rosbags says which format it refuses
        connections.append((meta['name'], meta['type'], meta.get('offered_qos_profiles', []),
                            meta.get('type_description_hash', '') or ''))
    paths = [folder / PurePath(name).name for name in info['relative_file_paths']]
    if not all(path.suffix == '.db3' and path.is_file() for path in paths):
        return None
    files = []
    for path in paths:
        database = _open_immutable(path)
        try:
            ids: dict[str, list[int]] = {}
            for topic_id, name, msgtype, encoding, qos, digest in _storage_topics(database):
                # rosbags' rule: name, type, serialisation and QoS agree; an empty hash agrees.
                for topic, wanted_type, wanted_qos, wanted_digest in connections:
                    if (topic, wanted_type, 'cdr') == (name, msgtype, encoding) and \
                            _qos_agree(wanted_qos, qos) and \
                            (not wanted_digest or not digest or wanted_digest == digest):
                        if keep(msgtype):
                            ids.setdefault(name, []).append(int(topic_id))
                        break
            files.append({name: topic_rows(database, sorted(set(found)))
                          for name, found in ids.items()})
        finally:
            database.close()
    return SqliteBag(int(info['message_count']), [(c[0], c[1]) for c in connections], files)


def read_sqlite(source: Path, keep: Callable[[str], bool]) -> SqliteBag | None:
    """
    Read an sqlite3 bag folder or ``.db3`` file, or say it is left to rosbags.

    Parameters
    ----------
    source : Path
        A bag folder with ``metadata.yaml``, a ``.db3`` file, or anything else (then None).
    keep : callable
        Given a topic's message type as the bag spells it, whether to read its messages.

    Returns
    -------
    SqliteBag or None
        The topics and the kept messages; None when rosbags must open the source.

    """
    try:
        if source.is_file() and source.suffix == '.db3':
            return _read_file(source, keep)
        if (source / 'metadata.yaml').is_file():
            return _read_folder(source, keep)
        return None
    except Exception:  # noqa: B902 - rosbags reads it or says what is wrong with it
        return None

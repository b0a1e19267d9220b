"""Opening a plain sqlite3 bag folder without rosbags."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path, PurePath
import sqlite3
from typing import Any, Callable

from hydro_sdp.bags.sqlite_rows import digests_agree, open_immutable, topic_rows, TopicRows
import yaml


@dataclass(frozen=True)
class PlainBag:
    """
    What a plain sqlite3 bag folder holds.

    Parameters
    ----------
    declared : int
        Messages the metadata counts.
    topics : list of tuple[str, str]
        ``(topic, msgtype)`` of every topic of the metadata, in its order.
    files : list of dict
        Per storage file, the rows of each kept topic that has any.

    """

    declared: int
    topics: list[tuple[str, str]]
    files: list[dict[str, TopicRows]]


def _qos(value: object) -> str | None:
    """Return comparable QoS text ('' for none), or None when it is not plain text."""
    if not value:
        return ''
    return value if isinstance(value, str) else None


def _metadata(folder: Path) -> dict[str, Any] | None:
    # Walked on trust: read_plain turns any key or type that is not there into None.
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


def _storage_topics(database: sqlite3.Connection) -> list[tuple[int, str, str, str, str, str]]:
    """Return ``(id, name, type, serialisation, qos, hash)`` of a storage file's topics."""
    tables = {row[0] for row in database.execute(
        "SELECT name FROM sqlite_master WHERE type = 'table'")}
    columns = {row[1] for row in database.execute('PRAGMA table_info(topics)')}
    if not {'messages', 'topics'} <= tables or 'offered_qos_profiles' not in columns:
        raise LookupError('not a storage file opened the plain way')
    schema = database.execute('SELECT schema_version FROM schema').fetchone()[0] \
        if 'schema' in tables else 2
    if schema >= 4 and 'message_definitions' not in tables:
        raise LookupError('schema 4 without message definitions')
    digest = 'type_description_hash' if schema >= 4 else "''"
    return database.execute(f'SELECT id, name, type, serialization_format, '
                            f'offered_qos_profiles, {digest} FROM topics').fetchall()


def read_plain(folder: Path, keep: Callable[[str], bool]) -> PlainBag | None:
    """
    Read a plain sqlite3 bag folder without rosbags, or say it is not one.

    Parameters
    ----------
    folder : Path
        A bag folder (with ``metadata.yaml``) or anything else (then None).
    keep : callable
        Given a topic's message type as the metadata spells it, whether to read it.

    Returns
    -------
    PlainBag or None
        The topics and the kept messages; None when rosbags must open the bag.

    """
    try:
        if not (folder / 'metadata.yaml').is_file():
            return None
        info = _metadata(folder)
        if info is None:
            return None
        connections = []
        for entry in info['topics_with_message_count']:
            meta = entry['topic_metadata']
            qos = _qos(meta.get('offered_qos_profiles', []))
            if meta['serialization_format'] != 'cdr' or qos is None:
                return None
            connections.append((meta['name'], meta['type'], qos,
                                meta.get('type_description_hash', '') or ''))
        paths = [folder / PurePath(name).name for name in info['relative_file_paths']]
        if not all(path.suffix == '.db3' and path.is_file() for path in paths):
            return None
        files = []
        for path in paths:
            database = open_immutable(path)
            try:
                ids: dict[str, list[int]] = {}
                for topic_id, name, msgtype, encoding, qos_text, digest in \
                        _storage_topics(database):
                    for topic, wanted_type, qos, wanted_digest in connections:
                        if (topic, wanted_type, 'cdr') != (name, msgtype, encoding):
                            continue
                        if qos != _qos(qos_text):
                            return None     # rosbags may still match them: let it judge
                        if digests_agree(wanted_digest, digest):
                            if keep(msgtype):
                                ids.setdefault(name, []).append(int(topic_id))
                            break
                files.append({name: topic_rows(database, sorted(set(found)))
                              for name, found in ids.items()})
            finally:
                database.close()
        return PlainBag(int(info['message_count']),
                        [(c[0], c[1]) for c in connections], files)
    except (OSError, sqlite3.Error, yaml.YAMLError, KeyError, TypeError, ValueError,
            LookupError, AttributeError):
        return None

"""
Rebuild ``metadata.yaml`` of a bag whose recorder was killed: rosbags has no reindex.

``hydro-sdp reindex`` and :class:`.live_writer.Sqlite3BagWriter` count the sqlite3 storage
files' messages per topic, as ``ros2 bag reindex`` does.
"""

from __future__ import annotations

from dataclasses import dataclass
import os
from pathlib import Path
import re
import sqlite3

from hydro_sdp.core.errors import BagFormatError, BagNotFoundError, BagReadError
from hydro_sdp.io.atomic import atomic_write_text
import yaml

#: Metadata version rosbag2 writes on Jazzy.
METADATA_VERSION = 8


@dataclass(frozen=True)
class TopicSummary:
    """
    One topic as a storage file declares it, with its message count.

    Parameters
    ----------
    name : str
        Topic name.
    msgtype : str
        Message type, e.g. ``std_msgs/msg/Bool``.
    serialization_format : str
        Usually ``cdr``.
    offered_qos_profiles : str
        The QoS text of the storage file, copied verbatim (readers match on it).
    type_description_hash : str
        ``RIHS01_...`` or empty.
    count : int
        Messages.

    """

    name: str
    msgtype: str
    serialization_format: str
    offered_qos_profiles: str
    type_description_hash: str
    count: int


@dataclass(frozen=True)
class FileSummary:
    """
    One storage file: its topics, message count and time span.

    Parameters
    ----------
    path : Path
        The ``.db3`` file.
    topics : tuple of TopicSummary
        Its topics (also those without messages).
    count : int
        Messages.
    start_ns, end_ns : int
        First and last receive time stamp, ns (0 for an empty file).

    """

    path: Path
    topics: tuple[TopicSummary, ...]
    count: int
    start_ns: int
    end_ns: int


@dataclass(frozen=True)
class BagSummary:
    """
    What a bag's storage files hold, as written to ``metadata.yaml``.

    Parameters
    ----------
    folder : Path
        Bag folder.
    files : tuple of FileSummary
        Storage files in their order in the bag.

    """

    folder: Path
    files: tuple[FileSummary, ...]

    @property
    def count(self) -> int:
        """Messages in the bag."""
        return sum(f.count for f in self.files)

    @property
    def start_ns(self) -> int:
        """First receive time stamp, ns (0 for an empty bag)."""
        starts = [f.start_ns for f in self.files if f.count]
        return min(starts) if starts else 0

    @property
    def duration_ns(self) -> int:
        """Last minus first receive time stamp, ns."""
        ends = [f.end_ns for f in self.files if f.count]
        return max(ends) - self.start_ns if ends else 0

    @property
    def topics(self) -> tuple[TopicSummary, ...]:
        """Topics over all files, counts summed, in order of first appearance."""
        merged: dict[tuple[str, str], TopicSummary] = {}
        for summary in self.files:
            for topic in summary.topics:
                key = (topic.name, topic.msgtype)
                if key in merged:
                    old = merged[key]
                    merged[key] = TopicSummary(old.name, old.msgtype, old.serialization_format,
                                               old.offered_qos_profiles,
                                               old.type_description_hash,
                                               old.count + topic.count)
                else:
                    merged[key] = topic
        return tuple(merged.values())


def _columns(connection: sqlite3.Connection, table: str) -> set[str]:
    return {row[1] for row in connection.execute(f'PRAGMA table_info({table})')}


def _open(path: Path) -> sqlite3.Connection:
    # Read-write when possible: sqlite rolls a hot journal (a transaction cut short by a
    # crash) back on first read, which needs write access.
    try:
        connection = sqlite3.connect(f'file:{path}?mode=rw', uri=True)
        connection.execute('SELECT count(*) FROM sqlite_master').fetchone()
        return connection
    except sqlite3.OperationalError:
        return sqlite3.connect(f'file:{path}?mode=ro', uri=True)


def summarise_file(path: str | os.PathLike[str]) -> FileSummary:
    """
    Count the messages of one sqlite3 storage file, per topic, and find its time span.

    Parameters
    ----------
    path : str or PathLike
        A ``.db3`` file written by rosbag2 (any schema since Foxy) or by ``bag_recorder``.

    Returns
    -------
    FileSummary
        Its topics, message count and time span.

    Raises
    ------
    BagReadError
        If the file is not an sqlite3 database with ``topics`` and ``messages`` tables.

    """
    source = Path(path)
    try:
        connection = _open(source)
    except sqlite3.Error as error:
        raise BagReadError(f'{source}: cannot open: {error}') from None
    try:
        columns = _columns(connection, 'topics')
        if not columns or not _columns(connection, 'messages'):
            raise BagReadError(f'{source}: not a rosbag2 sqlite3 file (no topics and '
                               'messages tables)')
        qos = 'offered_qos_profiles' if 'offered_qos_profiles' in columns else "''"
        digest = 'type_description_hash' if 'type_description_hash' in columns else "''"
        counts = dict(connection.execute(
            'SELECT topic_id, count(*) FROM messages GROUP BY topic_id').fetchall())
        topics = tuple(
            TopicSummary(name, msgtype, fmt, qos_text or '', hash_text or '',
                         counts.get(topic_id, 0))
            for topic_id, name, msgtype, fmt, qos_text, hash_text in connection.execute(
                f'SELECT id, name, type, serialization_format, {qos}, {digest} '
                'FROM topics ORDER BY id'))
        start, end, count = connection.execute(
            'SELECT min(timestamp), max(timestamp), count(*) FROM messages').fetchone()
    except sqlite3.DatabaseError as error:
        raise BagReadError(f'{source}: cannot read: {error}') from None
    finally:
        connection.close()
    return FileSummary(source, topics, int(count), int(start or 0), int(end or 0))


def _index(path: Path) -> tuple[str, int]:
    # rosbag2 names split files <bag>_<n>.db3: order them by n, as ros2 bag reindex does.
    match = re.fullmatch(r'(.*?)(?:_(\d+))?', path.stem)
    assert match is not None
    return match.group(1), int(match.group(2) or 0)


def summarise(folder: str | os.PathLike[str]) -> BagSummary:
    """
    Summarise every ``.db3`` storage file of a bag folder.

    Parameters
    ----------
    folder : str or PathLike
        Bag folder.

    Returns
    -------
    BagSummary
        Files in bag order with their topics and counts.

    Raises
    ------
    BagNotFoundError
        If the folder is missing or holds no ``.db3`` file.
    BagFormatError
        If it holds only ``.mcap`` files (not handled here).

    """
    bag = Path(folder)
    if not bag.is_dir():
        raise BagNotFoundError(f'{bag}: no such bag folder')
    files = sorted((p for p in bag.iterdir() if p.is_file() and p.suffix == '.db3'),
                   key=_index)
    if not files:
        if any(p.suffix == '.mcap' for p in bag.iterdir()):
            raise BagFormatError(f'{bag}: holds mcap storage; reindex handles sqlite3 (.db3) '
                                 'storage only')
        raise BagNotFoundError(f'{bag}: no .db3 storage file to reindex')
    return BagSummary(bag, tuple(summarise_file(p) for p in files))


def metadata_mapping(summary: BagSummary, ros_distro: str = '') -> dict:
    """
    Return the ``metadata.yaml`` document (version 8) of a summarised bag.

    Parameters
    ----------
    summary : BagSummary
        The bag.
    ros_distro : str
        Written as ``ros_distro``; default ``$ROS_DISTRO`` or ``jazzy``.

    Returns
    -------
    dict
        ``{'rosbag2_bagfile_information': {...}}``.

    """
    names = [f.path.name for f in summary.files]
    information = {
        'version': METADATA_VERSION,
        'storage_identifier': 'sqlite3',
        'duration': {'nanoseconds': summary.duration_ns},
        'starting_time': {'nanoseconds_since_epoch': summary.start_ns},
        'message_count': summary.count,
        'topics_with_message_count': [
            {'topic_metadata': {'name': t.name, 'type': t.msgtype,
                                'serialization_format': t.serialization_format,
                                'offered_qos_profiles': t.offered_qos_profiles,
                                'type_description_hash': t.type_description_hash},
             'message_count': t.count}
            for t in summary.topics],
        'compression_format': '',
        'compression_mode': '',
        'relative_file_paths': names,
        'files': [
            {'path': f.path.name,
             'starting_time': {'nanoseconds_since_epoch': f.start_ns},
             'duration': {'nanoseconds': f.end_ns - f.start_ns},
             'message_count': f.count}
            for f in summary.files],
        'custom_data': None,
        'ros_distro': ros_distro or os.environ.get('ROS_DISTRO', 'jazzy'),
    }
    return {'rosbag2_bagfile_information': information}


def write_metadata(summary: BagSummary) -> Path:
    """
    Write ``metadata.yaml`` of a summarised bag, whole or not at all.

    Parameters
    ----------
    summary : BagSummary
        The bag.

    Returns
    -------
    Path
        The metadata file.

    """
    text = yaml.safe_dump(metadata_mapping(summary), sort_keys=False, default_flow_style=False)
    return atomic_write_text(summary.folder / 'metadata.yaml', text)


def reindex(folder: str | os.PathLike[str]) -> BagSummary:
    """Rebuild ``metadata.yaml`` of a bag folder from its sqlite3 storage files."""
    summary = summarise(folder)
    write_metadata(summary)
    return summary

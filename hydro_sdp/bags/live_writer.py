"""
A recording cut short by a crash keeps all but its last second: rosbags' Writer commits at close.

rosbags writes sqlite3 storage in one transaction and metadata.yaml when it closes; this writer
commits at least once per ``flush_period`` (test/ros/test_recorder.py), in rosbag2's Jazzy
schema, and the recorder node imports it without rosbags.
"""

from __future__ import annotations

from contextlib import contextmanager
import os
from pathlib import Path
import sqlite3
import time
from typing import Callable, Iterator

from hydro_sdp.bags.reindex import BagSummary, metadata_mapping, METADATA_VERSION, reindex
from hydro_sdp.core.errors import BagWriteError
import yaml

#: The sqlite schema of rosbag2 on Jazzy (schema_version 4).
SCHEMA = """
CREATE TABLE schema(schema_version INTEGER PRIMARY KEY,ros_distro TEXT NOT NULL);
CREATE TABLE metadata(id INTEGER PRIMARY KEY,metadata_version INTEGER NOT NULL,
                      metadata TEXT NOT NULL);
CREATE TABLE topics(id INTEGER PRIMARY KEY,name TEXT NOT NULL,type TEXT NOT NULL,
                    serialization_format TEXT NOT NULL,offered_qos_profiles TEXT NOT NULL,
                    type_description_hash TEXT NOT NULL);
CREATE TABLE message_definitions(id INTEGER PRIMARY KEY,topic_type TEXT NOT NULL,
                                 encoding TEXT NOT NULL,
                                 encoded_message_definition TEXT NOT NULL,
                                 type_description_hash TEXT NOT NULL);
CREATE TABLE messages(id INTEGER PRIMARY KEY,topic_id INTEGER NOT NULL,
                      timestamp INTEGER NOT NULL, data BLOB NOT NULL);
CREATE INDEX timestamp_idx ON messages (timestamp ASC);
"""
SCHEMA_VERSION = 4


class Sqlite3BagWriter:
    """
    Write a new rosbag2 bag folder with one sqlite3 storage file.

    Parameters
    ----------
    folder : str or PathLike
        Bag folder to create; it must not exist.
    flush_period : float
        Longest time between commits while messages arrive, s (> 0).
    clock : callable
        Monotonic clock in seconds, for the flush period.

    Raises
    ------
    FileExistsError
        If ``folder`` exists (nothing there is touched).

    """

    def __init__(self, folder: str | os.PathLike[str], *, flush_period: float = 1.0,
                 clock: Callable[[], float] = time.monotonic) -> None:
        if not flush_period > 0.0:
            raise ValueError(f'flush_period must be > 0 s, got {flush_period!r}')
        self.folder = Path(folder)
        if self.folder.exists() or self.folder.is_symlink():
            raise FileExistsError(f'{self.folder} exists already; give a new output folder '
                                  '(the existing one was left untouched)')
        self.folder.parent.mkdir(parents=True, exist_ok=True)
        self.folder.mkdir()
        self.path = self.folder / f'{self.folder.name}_0.db3'
        self.flush_period = flush_period
        self._clock = clock
        # Autocommit mode: this class opens and commits its transactions itself.
        self._db: sqlite3.Connection | None = sqlite3.connect(
            self.path, isolation_level=None, check_same_thread=False)
        # A rollback journal keeps every commit readable by readers that ignore WAL files
        # (rosbags opens storage immutable); a crash mid-commit leaves a hot journal that
        # the next writer (reindex) rolls back.
        self._db.execute('PRAGMA journal_mode=DELETE')
        self._db.execute('PRAGMA synchronous=NORMAL')
        self._db.executescript(SCHEMA)
        self._db.execute('INSERT INTO schema VALUES(?, ?)',
                         (SCHEMA_VERSION, os.environ.get('ROS_DISTRO', 'jazzy')))
        self._types: set[str] = set()
        self.counts: dict[int, int] = {}
        self.pending = 0
        self._last_commit = clock()

    @property
    def closed(self) -> bool:
        """Whether :meth:`close` has run."""
        return self._db is None

    def _connection(self) -> sqlite3.Connection:
        if self._db is None:
            raise ValueError(f'{self.folder}: bag already closed')
        return self._db

    def add_topic(self, name: str, msgtype: str, *, msgdef: str = '',
                  msgdef_encoding: str = 'ros2msg', type_hash: str = '',
                  offered_qos_profiles: str = '', serialization_format: str = 'cdr') -> int:
        """Declare a topic and return its id for :meth:`write`."""
        db = self._connection()
        with self._writing(db):
            return self._add_topic(db, name, msgtype, msgdef, msgdef_encoding, type_hash,
                                   offered_qos_profiles, serialization_format)

    def _add_topic(self, db: sqlite3.Connection, name: str, msgtype: str, msgdef: str,
                   msgdef_encoding: str, type_hash: str, offered_qos_profiles: str,
                   serialization_format: str) -> int:
        self._begin(db)
        if msgtype not in self._types:
            db.execute('INSERT INTO message_definitions (topic_type, encoding, '
                       'encoded_message_definition, type_description_hash) VALUES(?, ?, ?, ?)',
                       (msgtype, msgdef_encoding, msgdef, type_hash))
            self._types.add(msgtype)
        cursor = db.execute('INSERT INTO topics (name, type, serialization_format, '
                            'offered_qos_profiles, type_description_hash) VALUES(?, ?, ?, ?, ?)',
                            (name, msgtype, serialization_format, offered_qos_profiles,
                             type_hash))
        topic_id = int(cursor.lastrowid or 0)
        self.counts[topic_id] = 0
        self.flush()
        return topic_id

    def _begin(self, db: sqlite3.Connection) -> None:
        if not db.in_transaction:
            db.execute('BEGIN')

    @contextmanager
    def _writing(self, db: sqlite3.Connection) -> Iterator[None]:
        # A write the disk refuses: what was not committed is rolled back, and one typed
        # error says what happened and what the bag holds.
        try:
            yield
        except sqlite3.Error as error:
            lost = self.pending
            try:
                if db.in_transaction:
                    db.execute('ROLLBACK')
            except sqlite3.Error:
                pass
            self.pending = 0
            raise BagWriteError(f'{self.path}: {error} (is the disk full?): the bag holds what '
                                f'was committed before; {lost} messages since were lost') \
                from None

    def write(self, topic_id: int, timestamp_ns: int, data: bytes) -> None:
        """
        Add one serialised message; commit if ``flush_period`` has passed.

        Parameters
        ----------
        topic_id : int
            From :meth:`add_topic`.
        timestamp_ns : int
            Receive time, ns.
        data : bytes
            CDR bytes.

        """
        db = self._connection()
        with self._writing(db):
            self._begin(db)
            db.execute('INSERT INTO messages (topic_id, timestamp, data) VALUES(?, ?, ?)',
                       (topic_id, int(timestamp_ns), data))
            self.counts[topic_id] += 1
            self.pending += 1
        self.flush_if_due()

    def flush_if_due(self) -> bool:
        """Commit if messages wait and ``flush_period`` has passed; return whether it did."""
        if self.pending and self._clock() - self._last_commit >= self.flush_period:
            self.flush()
            return True
        return False

    def flush(self) -> None:
        """Commit what was written so far."""
        db = self._connection()
        with self._writing(db):
            if db.in_transaction:
                db.execute('COMMIT')
        self.pending = 0
        self._last_commit = self._clock()

    @property
    def message_count(self) -> int:
        """Messages written (committed or not)."""
        return sum(self.counts.values())

    def close(self) -> BagSummary:
        """
        Commit, store the metadata in the database and write ``metadata.yaml``.

        Returns
        -------
        BagSummary
            What the bag holds.

        """
        db = self._connection()
        try:
            try:
                self.flush()
            except BagWriteError:
                pass                    # rolled back: the bag closes with what was committed
            summary = reindex(self.folder)
            text = yaml.safe_dump(metadata_mapping(summary)['rosbag2_bagfile_information'],
                                  sort_keys=False, default_flow_style=False)
            try:
                with self._writing(db):
                    db.execute('INSERT INTO metadata (metadata_version, metadata) '
                               'VALUES(?, ?)', (METADATA_VERSION, text.strip()))
            except BagWriteError:
                pass                    # metadata.yaml holds the same
        finally:
            db.close()
            self._db = None
        return summary

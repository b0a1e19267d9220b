"""
Any bag path read one way: rosbags' Reader refuses split files without metadata.yaml.

Each storage source goes to one reader: :mod:`.sqlite_reader` takes sqlite3 storage, rosbags'
Reader the rest (mcap, compression, what the sqlite3 reader leaves); rosbags' errors become
one-line ones.
"""

from __future__ import annotations

from dataclasses import dataclass
import os
from pathlib import Path
from typing import Callable, Iterable

from hydro_sdp.bags.sqlite_reader import read_sqlite
from hydro_sdp.core.errors import BagError, BagFormatError, BagNotFoundError, BagReadError

JOINT_STATE = 'sensor_msgs/msg/JointState'
FLOAT64 = 'std_msgs/msg/Float64'
STORAGE_SUFFIXES = ('.db3', '.mcap')
#: Storage plugins by the names users type.
STORAGES = ('sqlite3', 'mcap')

Progress = Callable[[int], None]


class EmptyBagError(BagError, ValueError):
    """The bag holds no messages."""


@dataclass(frozen=True)
class TopicInfo:
    """
    One topic of a bag.

    Parameters
    ----------
    name : str
        Topic name.
    msgtype : str
        Message type, e.g. ``sensor_msgs/msg/JointState``.
    count : int
        Messages read from the storage.

    """

    name: str
    msgtype: str
    count: int


@dataclass(frozen=True)
class BagInfo:
    """
    What a bag holds.

    Parameters
    ----------
    path : Path
        The bag as given.
    sources : tuple[Path, ...]
        What was opened: the bag folder, or its storage files.
    topics : tuple[TopicInfo, ...]
        Topics with their message counts.

    """

    path: Path
    sources: tuple[Path, ...]
    topics: tuple[TopicInfo, ...]

    @property
    def message_count(self) -> int:
        """Total messages read."""
        return sum(topic.count for topic in self.topics)

    def describe(self) -> str:
        """One-line list of the topics, for messages."""
        if not self.topics:
            return 'no topics'
        return ', '.join(f'{t.name} [{t.msgtype}]' for t in self.topics)


def _normalise_type(msgtype: str) -> str:
    # Old bags spell types without the '/msg/' part (test_msgs/BasicTypes).
    parts = msgtype.split('/')
    return f'{parts[0]}/msg/{parts[1]}' if len(parts) == 2 else msgtype


def _sources(path: Path) -> tuple[list[Path], bool]:
    """Return what to open, and whether it is a folder with metadata."""
    if not path.exists():
        raise BagNotFoundError(f'{path}: no such bag')
    if path.is_file():
        if path.name == 'metadata.yaml':
            return _sources(path.parent)
        if path.suffix not in STORAGE_SUFFIXES:
            raise BagFormatError(f'{path}: not a rosbag2 storage file (.db3 or .mcap)')
        return [path], False
    if (path / 'metadata.yaml').is_file():
        return [path], True
    files = _storage_files(path)
    if not files:
        raise BagNotFoundError(f'{path}: no metadata.yaml and no .db3 or .mcap storage file')
    return files, False


def _storage_files(folder: Path) -> list[Path]:
    return sorted(p for p in folder.iterdir() if p.is_file() and p.suffix in STORAGE_SUFFIXES)


@dataclass
class Collected:
    """Messages read from a bag's storage, by topic (raw CDR bytes, receive stamps in ns)."""

    topics: dict[str, list]  # name -> [msgtype, count]
    stamps: dict[str, list[int]]
    raws: dict[str, list[bytes]]
    declared: int = 0

    @property
    def kept(self) -> int:
        """Return the number of messages kept."""
        return sum(len(raws) for raws in self.raws.values())


def _read_sqlite(source: Path, keep: Callable[[str], bool], collected: Collected,
                 progress: Progress | None) -> bool:
    """Read an sqlite3 source in bulk; False when it is left to rosbags."""
    bag = read_sqlite(source, lambda msgtype: keep(_normalise_type(msgtype)))
    if bag is None:
        return False
    collected.declared += bag.declared
    for topic, msgtype in bag.topics:
        collected.topics.setdefault(topic, [_normalise_type(msgtype), 0])
    for rows in bag.files:
        for topic, (stamps, raws) in rows.items():
            if raws:
                collected.topics[topic][1] += len(raws)
                collected.stamps.setdefault(topic, []).extend(stamps)
                collected.raws.setdefault(topic, []).extend(raws)
        if progress is not None:
            progress(collected.kept)
    return True


def _read_with_rosbags(source: Path, keep: Callable[[str], bool], collected: Collected,
                       progress: Progress | None) -> None:
    """Read any source rosbags opens (mcap, compressed, what the sqlite3 reader leaves)."""
    from rosbags.rosbag2 import Reader, ReaderError

    try:
        with Reader(source) as reader:
            collected.declared += reader.message_count
            for connection in reader.connections:
                msgtype = _normalise_type(connection.msgtype)
                collected.topics.setdefault(connection.topic, [msgtype, 0])
            wanted = [c for c in reader.connections if keep(_normalise_type(c.msgtype))]
            for connection, timestamp, raw in reader.messages(connections=wanted):
                topic = connection.topic
                collected.topics[topic][1] += 1
                collected.stamps.setdefault(topic, []).append(timestamp)
                collected.raws.setdefault(topic, []).append(raw)
                if progress is not None and collected.kept % 50_000 == 0:
                    progress(collected.kept)
    except ReaderError as error:
        text = str(error)
        if 'format' in text.lower() and 'not supported' in text.lower():
            raise BagFormatError(f'{source}: {text}') from None
        raise BagReadError(f'{source}: cannot read bag: {text}') from None
    except BagError:
        raise
    except FileNotFoundError as error:
        raise BagNotFoundError(f'{source}: {error}') from None
    except Exception as error:  # noqa: B902 - storage libraries raise anything
        raise BagReadError(
            f'{source}: cannot read bag ({type(error).__name__}: {error})') from None


def _collect_from(sources: Iterable[Path], keep: Callable[[str], bool],
                  progress: Progress | None) -> Collected:
    collected = Collected({}, {}, {})
    for source in sources:
        # The one choice of reader: sqlite3 storage in bulk when it takes the source.
        if not _read_sqlite(source, keep, collected, progress):
            _read_with_rosbags(source, keep, collected, progress)
    return collected


def collect(path: Path, keep: Callable[[str], bool],
            progress: Progress | None = None) -> tuple[Collected, list[Path]]:
    """
    Read the messages of a bag whose type ``keep`` accepts.

    Parameters
    ----------
    path : Path
        Bag folder, storage file, or folder of split storage files.
    keep : callable
        Given a message type, whether to keep its messages.
    progress : callable or None
        Called now and then with the number of messages read so far.

    Returns
    -------
    tuple
        The messages, and what was opened (the folder or its storage files).

    """
    sources, is_folder = _sources(path)
    collected = _collect_from(sources, keep, progress)
    # A folder whose metadata names topics its storage files do not match (QoS of another
    # spelling, in rosbag2's own test bags) reads empty: its storage files are read then.
    if is_folder and collected.kept == 0:
        files = _storage_files(path)
        if files:
            direct = _collect_from(files, keep, progress)
            if direct.kept > 0:
                return direct, files
    return collected, sources


def raw_messages(path: str | os.PathLike[str]) -> list[tuple[str, str, int, bytes]]:
    """
    Every message of a bag as ``(topic, msgtype, timestamp_ns, raw CDR bytes)``.

    Parameters
    ----------
    path : str or PathLike
        The bag.

    Returns
    -------
    list of tuple
        In the order the storage returns them (by time).

    """
    collected, _ = collect(Path(path), lambda msgtype: True)
    out: list[tuple[str, str, int, bytes]] = []
    for topic, raws in collected.raws.items():
        msgtype = collected.topics[topic][0]
        out.extend((topic, msgtype, stamp, bytes(raw))
                   for stamp, raw in zip(collected.stamps[topic], raws))
    return sorted(out, key=lambda message: message[2])


def inspect_bag(path: str | os.PathLike[str]) -> BagInfo:
    """
    List a bag's topics and count its messages.

    Parameters
    ----------
    path : str or PathLike
        Bag folder, storage file, or folder of split storage files.

    Returns
    -------
    BagInfo
        Topics with the number of messages actually read.

    """
    bag = Path(path)
    collected, sources = collect(bag, lambda msgtype: True)
    topics = tuple(TopicInfo(name, msgtype, count)
                   for name, (msgtype, count) in sorted(collected.topics.items()))
    return BagInfo(bag, tuple(sources), topics)

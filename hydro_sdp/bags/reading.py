"""Bags to records on one time axis, each sample with its command: rosbags gives messages."""

from __future__ import annotations

from dataclasses import dataclass
import os
from pathlib import Path
from typing import Mapping, Sequence

from hydro_sdp.bags.cdr import decode_float64, decode_joint_states
from hydro_sdp.bags.storage import (
    BagInfo, collect, EmptyBagError, FLOAT64, JOINT_STATE, Progress, TopicInfo)
from hydro_sdp.core.arrays import FloatArray, IntArray
from hydro_sdp.core.errors import BagFormatError, DataError, JointNotFoundError, TopicNotFoundError
from hydro_sdp.core.model.records import Record
from hydro_sdp.core.model.timing import command_in_force
import numpy as np


@dataclass(frozen=True, eq=False)
class Series:
    """
    Samples of one ``std_msgs/msg/Float64`` topic.

    Parameters
    ----------
    topic : str
        Topic name.
    t : FloatArray
        Receive times, s from the bag's :attr:`BagData.start`.
    data : FloatArray
        Values.
    stamps : IntArray
        The same receive times in integer nanoseconds from the bag's start: what
        commands are paired with samples on.

    """

    topic: str
    t: FloatArray
    data: FloatArray
    stamps: IntArray


@dataclass(frozen=True, eq=False)
class BagData:
    """
    JointState and Float64 content of a bag, ready to become records.

    Parameters
    ----------
    path : Path
        The bag.
    state_topic : str
        The JointState topic read.
    t : FloatArray
        Time of each JointState message, s from :attr:`start` (``header.stamp``,
        or the receive time where the publisher left the stamps at zero).
    names : tuple[str, ...]
        Joint names.
    positions : FloatArray
        ``(messages, joints)`` positions in radians (NaN where a message lacks a joint).
    present : numpy.ndarray
        Whether each message named each joint.
    floats : Mapping[str, Series]
        Every Float64 topic.
    info : BagInfo
        The bag's topics.
    stamps : IntArray
        The times of ``t`` in integer nanoseconds from :attr:`start`.
    start : int
        Origin of the bag's times, ns since 1970 (or since the clock's zero): the whole second at
        or before its first message.

    """

    path: Path
    state_topic: str
    t: FloatArray
    names: tuple[str, ...]
    positions: FloatArray
    present: np.ndarray
    floats: Mapping[str, Series]
    info: BagInfo
    stamps: IntArray
    start: int = 0

    def angles(self, joint: str) -> tuple[FloatArray, FloatArray]:
        """
        Time and angle (degrees) of the messages that name ``joint``.

        Parameters
        ----------
        joint : str
            Joint name.

        Returns
        -------
        tuple of FloatArray
            ``(t, y)``.

        """
        if joint not in self.names:
            joints = ', '.join(self.names)
            raise JointNotFoundError(f'{self.path}: joint {joint!r} is not in {self.state_topic} '
                                     f'(joints: {joints})')
        column = self.names.index(joint)
        mask = self.present[:, column]
        return self.t[mask], np.degrees(self.positions[mask, column])

    def choose_joint(self, joint: str | None) -> str:
        """Return ``joint``, or the only joint of the bag when it is ``None``."""
        if joint is not None:
            if joint not in self.names:
                raise JointNotFoundError(f'{self.path}: joint {joint!r} is not in '
                                         f"{self.state_topic} (joints: {', '.join(self.names)})")
            return joint
        if len(self.names) != 1:
            raise JointNotFoundError(f"{self.path}: the bag has joints {', '.join(self.names)}; "
                                     'choose one with --joint')
        return self.names[0]

    def command_topic(self, joint: str, topic: str | None = None) -> str:
        """
        Find the Float64 command topic of ``joint``.

        Parameters
        ----------
        joint : str
            Joint name, used to choose among several ``valve_command`` topics.
        topic : str or None
            Topic asked for by the user; checked to be a Float64 topic of the bag.

        Returns
        -------
        str
            Topic name.

        """
        if topic is not None:
            if topic in self.floats:
                return topic
            for info in self.info.topics:
                if info.name == topic:
                    raise TopicNotFoundError(
                        f'{self.path}: topic {topic} is {info.msgtype}, not {FLOAT64}')
            raise TopicNotFoundError(f'{self.path}: no topic {topic} '
                                     f'(topics: {self.info.describe()})')
        candidates = [name for name in self.floats if name.endswith('valve_command')]
        if len(candidates) > 1:
            own = [name for name in candidates
                   if name.rstrip('/').endswith(f'{joint}/valve_command')]
            candidates = own if len(own) == 1 else candidates
        if len(candidates) == 1:
            return candidates[0]
        if not candidates:
            raise TopicNotFoundError(f'{self.path}: no {FLOAT64} topic ending in valve_command '
                                     f'(topics: {self.info.describe()})')
        raise TopicNotFoundError(f"{self.path}: several command topics ({', '.join(candidates)}); "
                                 'choose one with --command-topic')

    def record(self, joint: str | None = None, command_topic: str | None = None, *,
               load_topic: str | None = None, others: bool = False) -> Record:
        """
        One joint's angle with the command in force before each angle sample.

        Parameters
        ----------
        joint : str or None
            Joint name; default: the only joint in the bag.
        command_topic : str or None
            Float64 command topic; default: the only topic ending in ``valve_command``.
        load_topic : str or None
            Float64 topic of a measured load (a cylinder pressure, say), held like the command
            (:func:`hydro_sdp.core.model.timing.command_in_force`) into the record's ``load``;
            angle samples before its first message are dropped.
        others : bool
            Whether to carry the angles of the bag's other joints (those named in
            every message that names ``joint``) as the record's ``others``.

        Returns
        -------
        Record
            ``t`` (s), ``v`` (input units), ``y`` (degrees).

        """
        joint = self.choose_joint(joint)
        topic = self.command_topic(joint, command_topic)
        t, y = self.angles(joint)
        stamps = self.stamps[self.present[:, self.names.index(joint)]]
        command, index = self._held(topic, stamps, 'command')
        keep = index >= 0
        if not keep.any():
            raise DataError(f'{self.path}: no {topic} message arrives before the last '
                            f'{self.state_topic} sample')
        load, held = self._load(load_topic, stamps)
        if load is not None:
            keep &= held >= 0
            if not keep.any():
                raise DataError(f'{self.path}: no {load_topic} message arrives before the '
                                f'last {self.state_topic} sample')
        names, angles = self._others(joint) if others else ((), None)
        return Record(t[keep], command[index[keep]], y[keep], joint=joint, source=str(self.path),
                      origin=float(self.t[0]),
                      load=None if load is None else load[held[keep]],
                      others=None if angles is None else angles[keep], other_joints=names)

    def _load(self, topic: str | None,
              stamps: IntArray) -> tuple[FloatArray | None, IntArray]:
        """Values of the load topic and, per angle sample, the index of the one in force."""
        if topic is None:
            return None, np.zeros(0, dtype=np.int64)
        if topic not in self.floats:
            raise TopicNotFoundError(f'{self.path}: no {FLOAT64} load topic {topic} '
                                     f'(topics: {self.info.describe()})')
        return self._held(topic, stamps, 'load')

    def _held(self, topic: str, stamps: IntArray,
              what: str) -> tuple[FloatArray, IntArray]:
        """Values of a Float64 topic in time order, and the one in force at each stamp (ns)."""
        series = self.floats[topic]
        if series.stamps.size == 0:
            raise DataError(f'{self.path}: {what} topic {topic} has no messages')
        order = np.argsort(series.stamps, kind='stable')
        return series.data[order], command_in_force(stamps, series.stamps[order])

    def _others(self, joint: str) -> tuple[tuple[str, ...], FloatArray | None]:
        """Names and angles (degrees) of the other joints measured wherever ``joint`` is."""
        mask = self.present[:, self.names.index(joint)]
        # A joint the publisher cannot measure (NaN) is left out, as a joint not sent.
        columns = [i for i, name in enumerate(self.names)
                   if name != joint and bool(np.all(self.present[mask, i]))
                   and bool(np.all(np.isfinite(self.positions[mask, i])))]
        if not columns:
            return (), None
        return (tuple(self.names[i] for i in columns),
                np.degrees(self.positions[mask][:, columns]))


def read_bag(path: str | os.PathLike[str], *, state_topic: str | None = None,
             progress: Progress | None = None) -> BagData:
    """
    Read the JointState and Float64 topics of a bag.

    Parameters
    ----------
    path : str or PathLike
        Bag folder, storage file, or folder of split storage files.
    state_topic : str or None
        JointState topic; default: the only one in the bag.
    progress : callable or None
        Called now and then with the number of messages read so far.

    Returns
    -------
    BagData
        The decoded content.

    """
    bag = Path(path)
    collected, sources = collect(bag, lambda msgtype: msgtype in (JOINT_STATE, FLOAT64),
                                 progress)
    topics = tuple(TopicInfo(name, msgtype, count)
                   for name, (msgtype, count) in sorted(collected.topics.items()))
    info = BagInfo(bag, tuple(sources), topics)
    if collected.kept == 0 and collected.declared == 0:
        raise EmptyBagError(f'{bag}: the bag holds no messages')
    state_topics = [name for name, (msgtype, _) in collected.topics.items()
                    if msgtype == JOINT_STATE]
    if state_topic is None:
        if not state_topics:
            raise TopicNotFoundError(f'{bag}: no {JOINT_STATE} topic (topics: {info.describe()})')
        if len(state_topics) > 1:
            preferred = [t for t in state_topics if t.rstrip('/').endswith('joint_states')]
            if len(preferred) != 1:
                listed = ', '.join(state_topics)
                raise TopicNotFoundError(f'{bag}: several JointState topics ({listed}); '
                                         'choose one')
            state_topics = preferred
        state_topic = state_topics[0]
    elif state_topic not in state_topics:
        raise TopicNotFoundError(f'{bag}: no {JOINT_STATE} topic {state_topic} '
                                 f'(topics: {info.describe()})')
    raws = collected.raws.get(state_topic, [])
    if not raws:
        raise DataError(f'{bag}: topic {state_topic} has no messages')
    try:
        decoded = decode_joint_states(raws)
        receive = np.asarray(collected.stamps[state_topic], dtype=np.int64)
        series = {name: (np.asarray(collected.stamps.get(name, []), dtype=np.int64),
                         decode_float64(collected.raws.get(name, [])))
                  for name, (msgtype, _) in collected.topics.items() if msgtype == FLOAT64}
    except (TypeError, ValueError, OverflowError) as error:
        if isinstance(error, BagFormatError):
            raise
        # A damaged storage file can hand back NULL or mistyped time stamps and payloads.
        raise BagFormatError(f'{bag}: malformed messages or time stamps ({error})') from None
    # A publisher that never fills header.stamp leaves it at zero; use receive times then.
    stamps = receive if not decoded.stamps.any() else np.asarray(decoded.stamps, dtype=np.int64)
    start = recording_start([stamps] + [times for times, _ in series.values()])
    floats = {name: Series(name, seconds_since(times, start), values, times - start)
              for name, (times, values) in series.items()}
    return BagData(bag, state_topic, seconds_since(stamps, start), decoded.names,
                   decoded.positions, decoded.present, floats, info, stamps - start, start)


#: Nanoseconds in a second.
NANOSECONDS = 1_000_000_000


def recording_start(stamps: Sequence[IntArray]) -> int:
    """
    Return the whole second (ns) at or before the earliest of integer nanosecond stamps.

    Parameters
    ----------
    stamps : sequence of IntArray
        Stamps of every topic read, ns.

    Returns
    -------
    int
        The origin the bag's times count from, ns.

    """
    firsts = [int(np.min(times)) for times in stamps if np.asarray(times).size]
    return (min(firsts) // NANOSECONDS) * NANOSECONDS if firsts else 0


def seconds_since(stamps: IntArray, start: int) -> FloatArray:
    """Integer nanosecond stamps as seconds from ``start`` (ns), subtracted as integers."""
    return np.asarray((np.asarray(stamps, dtype=np.int64) - np.int64(start)) * 1e-9,
                      dtype=np.float64)


def read_record(path: str | os.PathLike[str], joint: str | None = None,
                command_topic: str | None = None) -> Record:
    """Read one joint's record from a bag (see :meth:`BagData.record`)."""
    return read_bag(path).record(joint, command_topic)

"""
JointState and Float64 CDR in bulk: 60x faster to decode, 20x to encode than rosbags' typestore.

rosbags (de)serialises one message object at a time; these codecs read and fill whole arrays
of messages that share a layout (bench/bench_bags.py, a one-hour 100 Hz bag).
"""

from __future__ import annotations

from dataclasses import dataclass
import struct
from typing import Sequence

from hydro_sdp.core.arrays import FloatArray
from hydro_sdp.core.errors import BagFormatError
import numpy as np

_LITTLE_ENDIAN_HEADERS = (b'\x00\x01', b'\x00\x03')
_BIG_ENDIAN_HEADERS = (b'\x00\x00', b'\x00\x02')


@dataclass(frozen=True)
class JointStateLayout:
    """
    Where the fields of one CDR-encoded JointState message lie.

    Parameters
    ----------
    little_endian : bool
        Byte order of the message.
    names : tuple[str, ...]
        Joint names.
    position_offset : int
        Byte offset of the first position in the raw message.
    position_count : int
        Number of positions.

    """

    little_endian: bool
    names: tuple[str, ...]
    position_offset: int
    position_count: int


def _byte_order(raw: bytes | memoryview) -> bool:
    header = bytes(raw[:2])
    if header in _LITTLE_ENDIAN_HEADERS:
        return True
    if header in _BIG_ENDIAN_HEADERS:
        return False
    raise BagFormatError(f'unknown CDR encapsulation {header.hex()}')


def joint_state_layout(raw: bytes | memoryview) -> JointStateLayout:
    """
    Walk one CDR JointState message and locate its names and positions.

    Parameters
    ----------
    raw : bytes or memoryview
        Serialised message including the 4-byte encapsulation header.

    Returns
    -------
    JointStateLayout
        The layout.

    """
    try:
        little = _byte_order(raw)
        u32 = struct.Struct('<I' if little else '>I')
        body = memoryview(raw)[4:]
        offset = 8  # stamp.sec, stamp.nanosec
        frame_length = u32.unpack_from(body, offset)[0]
        offset += 4 + frame_length
        offset = (offset + 3) & ~3
        count = u32.unpack_from(body, offset)[0]
        offset += 4
        names = []
        for _ in range(count):
            offset = (offset + 3) & ~3
            length = u32.unpack_from(body, offset)[0]
            names.append(bytes(body[offset + 4:offset + 4 + length - 1]).decode('utf-8'))
            offset += 4 + length
        offset = (offset + 3) & ~3
        positions = u32.unpack_from(body, offset)[0]
        offset += 4
        if positions:
            offset = (offset + 7) & ~7
        if offset + 8 * positions > len(body):
            raise BagFormatError('JointState message is shorter than its position array')
    except (struct.error, UnicodeDecodeError) as error:
        raise BagFormatError(f'malformed JointState message: {error}') from None
    return JointStateLayout(little, tuple(names), 4 + offset, positions)


def _decode_one(raw: bytes) -> tuple[int, tuple[str, ...], FloatArray]:
    layout = joint_state_layout(raw)
    order = '<' if layout.little_endian else '>'
    sec, nanosec = struct.unpack_from(order + 'iI', raw, 4)
    positions = np.frombuffer(raw, dtype=order + 'f8', count=layout.position_count,
                              offset=layout.position_offset).astype(np.float64)
    return sec * 1_000_000_000 + nanosec, layout.names, positions


@dataclass(frozen=True, eq=False)
class DecodedJointStates:
    """
    Stamps and positions of a JointState stream.

    Parameters
    ----------
    stamps : numpy.ndarray
        ``header.stamp`` of each message, integer nanoseconds.
    names : tuple[str, ...]
        Every joint name seen, in order of first appearance.
    positions : FloatArray
        ``(messages, joints)`` positions in radians; NaN where a message lacks the joint.
    present : numpy.ndarray
        ``(messages, joints)`` booleans: whether the message named the joint.

    """

    stamps: np.ndarray
    names: tuple[str, ...]
    positions: FloatArray
    present: np.ndarray


def decode_joint_states(raws: Sequence[bytes]) -> DecodedJointStates:
    """
    Decode many CDR JointState messages, in bulk where their layouts agree.

    Parameters
    ----------
    raws : sequence of bytes
        Serialised messages.

    Returns
    -------
    DecodedJointStates
        Stamps, names and positions, in the order of ``raws``.

    """
    count = len(raws)
    stamps = np.zeros(count, dtype=np.int64)
    names: dict[str, int] = {}
    rows: list[tuple[np.ndarray, tuple[str, ...], FloatArray]] = []
    lengths = np.fromiter(map(len, raws), dtype=np.int64, count=count)
    for length in np.unique(lengths):
        index = np.flatnonzero(lengths == length)
        first = raws[int(index[0])]
        layout = joint_state_layout(first)
        # One publisher's messages all have one length: join them as they are.
        chosen = raws if index.size == count else [raws[i] for i in index.tolist()]
        block = np.frombuffer(b''.join(chosen), dtype=np.uint8).reshape(index.size, int(length))
        template = np.frombuffer(first, dtype=np.uint8)
        # Same bytes outside the stamp (4:12) and the positions: header, frame id, names.
        start = layout.position_offset
        same = (block[:, :4] == template[:4]).all(axis=1) & \
            (block[:, 12:start] == template[12:start]).all(axis=1)
        order = '<' if layout.little_endian else '>'
        bulk = index[same]
        if bulk.size:
            rows_same = block if bulk.size == index.size else block[same]
            sec = np.ascontiguousarray(rows_same[:, 4:8]).view(order + 'i4')[:, 0]
            nanosec = np.ascontiguousarray(rows_same[:, 8:12]).view(order + 'u4')[:, 0]
            stamps[bulk] = sec.astype(np.int64) * 1_000_000_000 + nanosec
            end = layout.position_offset + 8 * layout.position_count
            values = np.ascontiguousarray(rows_same[:, layout.position_offset:end])
            rows.append((bulk, layout.names,
                         values.view(order + 'f8').astype(np.float64, copy=False)))
        for i in index[~same]:
            stamp, message_names, positions = _decode_one(raws[i])
            stamps[i] = stamp
            rows.append((np.array([i]), message_names, positions[np.newaxis, :]))
    for _, message_names, _ in rows:
        for name in message_names:
            names.setdefault(name, len(names))
    positions_out = np.full((count, len(names)), np.nan)
    present = np.zeros((count, len(names)), dtype=bool)
    for index, message_names, values in rows:
        if len(message_names) != values.shape[1]:
            raise BagFormatError(f'JointState message has {len(message_names)} names but '
                                 f'{values.shape[1]} positions')
        columns = np.array([names[name] for name in message_names], dtype=np.int64)
        positions_out[np.ix_(index, columns)] = values
        present[np.ix_(index, columns)] = True
    return DecodedJointStates(stamps, tuple(names), positions_out, present)


def decode_float64(raws: Sequence[bytes]) -> FloatArray:
    """
    Decode many CDR ``std_msgs/msg/Float64`` messages.

    Parameters
    ----------
    raws : sequence of bytes
        Serialised messages of 12 bytes each.

    Returns
    -------
    FloatArray
        The ``data`` fields.

    """
    if not raws:
        return np.empty(0)
    block = np.frombuffer(b''.join(raws), dtype=np.uint8)
    if block.size != 12 * len(raws):
        raise BagFormatError('a Float64 message is not 12 bytes long')
    block = block.reshape(len(raws), 12)
    little = block[:, 1] % 2 == 1
    if not ((block[:, 0] == 0) & (block[:, 2:4] == 0).all(axis=1)).all():
        raise BagFormatError('a Float64 message has an unknown CDR encapsulation')
    data = np.ascontiguousarray(block[:, 4:])
    values = data.view('<f8')[:, 0].copy()
    if not little.all():
        values[~little] = data[~little].view('>f8')[:, 0]
    return values


def encode_float64(values: FloatArray) -> list[bytes]:
    """
    Encode values as little-endian CDR ``std_msgs/msg/Float64`` messages.

    Parameters
    ----------
    values : FloatArray
        The ``data`` fields.

    Returns
    -------
    list of bytes
        One 12-byte message per value.

    """
    block = np.empty((len(values), 12), dtype=np.uint8)
    block[:, :4] = np.frombuffer(b'\x00\x01\x00\x00', dtype=np.uint8)
    block[:, 4:] = np.asarray(values, dtype='<f8').reshape(-1, 1).view(np.uint8)
    data = block.tobytes()
    return [data[i:i + 12] for i in range(0, len(data), 12)]


def encode_joint_states(template: bytes, stamps: np.ndarray, positions: FloatArray) -> list[bytes]:
    """
    Fill a serialised JointState template with many stamps and position rows.

    Parameters
    ----------
    template : bytes
        One little-endian message with the right frame id, names and number of
        positions (as serialised by rosbags); its stamp and positions are replaced.
    stamps : numpy.ndarray
        Integer nanoseconds per message.
    positions : FloatArray
        ``(messages, joints)`` positions in radians.

    Returns
    -------
    list of bytes
        The messages.

    """
    layout = joint_state_layout(template)
    if not layout.little_endian:
        raise BagFormatError('the JointState template must be little-endian')
    positions = np.asarray(positions, dtype='<f8')
    count = positions.shape[0]
    if positions.shape[1] != layout.position_count:
        raise BagFormatError(f'{positions.shape[1]} positions for a template of '
                             f'{layout.position_count}')
    size = len(template)
    block = np.tile(np.frombuffer(template, dtype=np.uint8), (count, 1))
    stamps = np.asarray(stamps, dtype=np.int64)
    block[:, 4:8] = (stamps // 1_000_000_000).astype('<i4').reshape(-1, 1).view(np.uint8)
    block[:, 8:12] = (stamps % 1_000_000_000).astype('<u4').reshape(-1, 1).view(np.uint8)
    end = layout.position_offset + 8 * layout.position_count
    block[:, layout.position_offset:end] = np.ascontiguousarray(positions).view(np.uint8)
    data = block.tobytes()
    return [data[i:i + size] for i in range(0, len(data), size)]

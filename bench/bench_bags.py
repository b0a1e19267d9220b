"""
Benchmark what hydro_sdp.bags does beside rosbags, each against rosbags in the same run.

Run with ``python bench/bench_bags.py``. Prints, for a one-hour 100 Hz bag (JointState +
Float64, 720,000 messages):

* seconds to read its sqlite3 storage with :mod:`hydro_sdp.bags.sqlite_reader` against
  rosbags' Reader (``Reader.messages``), for a bag this package writes and for one with
  Jazzy's QoS lists in its metadata (target: at least 1.5x faster);
* seconds to decode its messages with :mod:`hydro_sdp.bags.cdr` against rosbags'
  ``deserialize_cdr``, and to encode them against ``serialize_cdr`` (target: at least 5x).

"""

import argparse
from pathlib import Path
import tempfile

from bench_foundation import best_of
from hydro_sdp.bags import storage, write_bag
from hydro_sdp.bags.cdr import (
    decode_float64, decode_joint_states, encode_float64, encode_joint_states)
from hydro_sdp.core.model.records import Record
import numpy as np
from rosbags.interfaces import Qos, QosDurability, QosHistory, QosLiveliness, QosReliability
from rosbags.interfaces import QosTime
from rosbags.rosbag2 import Reader, StoragePlugin, Writer
from rosbags.typesys import get_typestore, Stores

TYPESTORE = get_typestore(Stores.ROS2_JAZZY)
FOREVER = QosTime(9223372036, 854775807)
#: What ``ros2 bag record`` on Jazzy records for a default publisher.
QOS = Qos(QosHistory.UNKNOWN, 0, QosReliability.RELIABLE, QosDurability.VOLATILE, FOREVER,
          FOREVER, QosLiveliness.AUTOMATIC, FOREVER, False)


def _jazzy_copy(bag, path):
    """Copy a bag as rosbag2 on Jazzy writes it: metadata version 9, QoS as YAML lists."""
    with Reader(bag) as reader, Writer(path, version=9,
                                       storage_plugin=StoragePlugin.SQLITE3) as writer:
        added = {c.id: writer.add_connection(c.topic, c.msgtype, typestore=TYPESTORE,
                                             offered_qos_profiles=[QOS])
                 for c in reader.connections}
        for connection, stamp, raw in reader.messages():
            writer.write(added[connection.id], stamp, raw)
    return path


def _collect(bag, route):
    """Collect every message of a bag by the sqlite3 reader or by rosbags' Reader."""
    if route == 'sqlite':
        return storage.collect(bag, lambda msgtype: True)[0]
    collected = storage.Collected({}, {}, {})
    storage._read_with_rosbags(bag, lambda msgtype: True, collected, None)
    return collected


def main():
    """Run the benchmarks and print the figures."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('--hours', type=float, default=1.0, help='bag length (default: 1 h)')
    args = parser.parse_args()
    samples = int(round(args.hours * 3600 * 100))
    t = np.arange(1, samples + 1) * 0.01
    record = Record(t, np.sin(t), 30.0 * np.cos(t), joint='j2')
    with tempfile.TemporaryDirectory() as folder:
        bag = write_bag(Path(folder) / 'package', [record])
        bags = {'written by hydro_sdp': bag, 'Jazzy QoS lists': _jazzy_copy(bag, Path(folder) /
                                                                            'jazzy')}
        print(f'reading the sqlite3 storage of {2 * samples:,} messages')
        for name, path in bags.items():
            ours, fast = best_of(3, lambda: _collect(path, 'sqlite'))
            theirs, slow = best_of(1, lambda: _collect(path, 'rosbags'))
            assert fast.stamps == slow.stamps and fast.raws == slow.raws
            print(f'  {name:22s} sqlite_reader {ours:5.2f} s, rosbags Reader {theirs:5.2f} s: '
                  f'{theirs / ours:.1f}x (target >= 1.5x)')
        collected = _collect(bag, 'sqlite')
    states = collected.raws['/joint_states']
    floats = collected.raws['/j2/valve_command']
    ours, decoded = best_of(3, lambda: (decode_joint_states(states), decode_float64(floats)))
    theirs, messages = best_of(1, lambda: (
        [TYPESTORE.deserialize_cdr(raw, 'sensor_msgs/msg/JointState') for raw in states],
        [TYPESTORE.deserialize_cdr(raw, 'std_msgs/msg/Float64') for raw in floats]))
    assert np.array_equal(decoded[0].positions[:, 0], [m.position[0] for m in messages[0]])
    assert np.array_equal(decoded[1], [m.data for m in messages[1]])
    print(f'decoding {len(states) + len(floats):,} messages')
    print(f'  cdr {ours:5.2f} s, rosbags deserialize_cdr {theirs:5.2f} s: {theirs / ours:.1f}x '
          '(target >= 5x)')
    template = states[0]
    stamps = np.asarray(decoded[0].stamps)
    positions = decoded[0].positions
    ours, encoded = best_of(3, lambda: (encode_joint_states(template, stamps, positions),
                                        encode_float64(decoded[1])))
    theirs, serialised = best_of(1, lambda: (
        [bytes(TYPESTORE.serialize_cdr(m, 'sensor_msgs/msg/JointState')) for m in messages[0]],
        [bytes(TYPESTORE.serialize_cdr(m, 'std_msgs/msg/Float64')) for m in messages[1]]))
    assert encoded == serialised
    print(f'encoding {len(states) + len(floats):,} messages')
    print(f'  cdr {ours:5.2f} s, rosbags serialize_cdr {theirs:5.2f} s: {theirs / ours:.1f}x '
          '(target >= 5x)')


if __name__ == '__main__':
    main()

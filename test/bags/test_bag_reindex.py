"""The crash-safe sqlite3 bag writer and ``hydro-sdp reindex``, without ROS."""

import json
import subprocess
import sys
import textwrap

from conftest import FIXTURES, REPO
from hydro_sdp.bags import read_bag, write_bag
from hydro_sdp.bags.live_writer import Sqlite3BagWriter
from hydro_sdp.bags.reindex import reindex, summarise
from hydro_sdp.cli.main import main
from hydro_sdp.core.errors import BagFormatError, BagNotFoundError, BagWriteError
from hydro_sdp.core.model.records import Record
import numpy as np
import pytest
from rosbags.rosbag2 import Reader
from rosbags.typesys import get_typestore, Stores
import yaml

TYPESTORE = get_typestore(Stores.ROS2_JAZZY)

# Writes 250 Bool and 250 Float64 messages, one pair per 0.01 s of a fake clock, with
# flush_period 1 s, then dies without closing: commits happened at t = 1.00 s and 2.00 s.
CRASH = textwrap.dedent("""
    import os, sys
    from hydro_sdp.bags.live_writer import Sqlite3BagWriter
    from rosbags.typesys import get_typestore, Stores
    store = get_typestore(Stores.ROS2_JAZZY)
    now = [0.0]
    writer = Sqlite3BagWriter(sys.argv[1], flush_period=1.0, clock=lambda: now[0])
    msgdef, _ = store.generate_msgdef('std_msgs/msg/Bool', ros_version=2)
    flag = writer.add_topic('/flag', 'std_msgs/msg/Bool', msgdef=msgdef,
                            type_hash=store.hash_rihs01('std_msgs/msg/Bool'))
    value = writer.add_topic('/value', 'std_msgs/msg/Float64')
    Bool, Float64 = store.types['std_msgs/msg/Bool'], store.types['std_msgs/msg/Float64']
    for k in range(250):
        now[0] = k * 0.01
        stamp = 10**9 + k * 10**7
        writer.write(flag, stamp, bytes(store.serialize_cdr(Bool(data=k % 2 == 0),
                                                            'std_msgs/msg/Bool')))
        writer.write(value, stamp, bytes(store.serialize_cdr(Float64(data=float(k)),
                                                             'std_msgs/msg/Float64')))
    os._exit(0)
""")


def _crashed_bag(folder):
    result = subprocess.run([sys.executable, '-c', CRASH, str(folder)], capture_output=True,
                            text=True, timeout=60, env={'PYTHONPATH': str(REPO)})
    assert result.returncode == 0, result.stderr
    return folder


def test_a_crashed_writer_keeps_every_committed_message(tmp_path):
    bag = _crashed_bag(tmp_path / 'bag')
    assert not (bag / 'metadata.yaml').exists()
    summary = reindex(bag)
    # The commit at t = 2.00 s came after the Bool of k = 200 and before its Float64.
    counts = {t.name: (t.msgtype, t.count) for t in summary.topics}
    assert counts == {'/flag': ('std_msgs/msg/Bool', 201),
                      '/value': ('std_msgs/msg/Float64', 200)}
    assert (summary.start_ns, summary.duration_ns) == (10**9, 2 * 10**9)
    metadata = yaml.safe_load((bag / 'metadata.yaml').read_text())['rosbag2_bagfile_information']
    assert metadata['version'] == 8 and metadata['message_count'] == 401
    assert metadata['relative_file_paths'] == ['bag_0.db3']
    with Reader(bag) as reader:
        assert reader.message_count == 401
        assert reader.duration == 2 * 10**9 + 1
        flags = [TYPESTORE.deserialize_cdr(raw, c.msgtype).data
                 for c, _, raw in reader.messages() if c.topic == '/flag']
        values = [TYPESTORE.deserialize_cdr(raw, c.msgtype).data
                  for c, _, raw in reader.messages() if c.topic == '/value']
    assert flags == [k % 2 == 0 for k in range(201)]
    assert values == [float(k) for k in range(200)]


def test_a_closed_writer_writes_metadata_that_bag_tools_read(tmp_path):
    record = Record(np.arange(1, 51) * 0.01, np.linspace(-1, 1, 50), np.linspace(0, 5, 50),
                    joint='j2')
    source = write_bag(tmp_path / 'source', [record])
    writer = Sqlite3BagWriter(tmp_path / 'copy')
    with Reader(source) as reader:
        ids = {c.topic: writer.add_topic(c.topic, c.msgtype) for c in reader.connections}
        for connection, stamp, raw in reader.messages():
            writer.write(ids[connection.topic], stamp, raw)
    summary = writer.close()
    assert summary.count == 100 and writer.closed
    copy, original = read_bag(tmp_path / 'copy'), read_bag(source)
    np.testing.assert_array_equal(copy.t, original.t)
    np.testing.assert_array_equal(copy.positions, original.positions)
    assert copy.record().v.tolist() == original.record().v.tolist()


def test_a_full_disk_stops_the_writer_and_the_bag_keeps_what_was_committed(tmp_path):
    now = [0.0]
    writer = Sqlite3BagWriter(tmp_path / 'bag', flush_period=1.0, clock=lambda: now[0])
    value = writer.add_topic('/value', 'std_msgs/msg/Float64')
    Float64 = TYPESTORE.types['std_msgs/msg/Float64']
    raw = bytes(TYPESTORE.serialize_cdr(Float64(data=1.0), 'std_msgs/msg/Float64'))
    for k in range(100):                        # committed at 1 s
        now[0] = k * 0.02
        writer.write(value, 10**9 + k * 10**7, raw)
    # The disk is full: sqlite may not grow the file past the pages it has.
    pages = writer._db.execute('PRAGMA page_count').fetchone()[0]
    writer._db.execute(f'PRAGMA max_page_count={pages}')
    with pytest.raises(BagWriteError, match=r'bag_0\.db3: database or disk is full \(is the '
                                            r'disk full\?\): the bag holds what was committed '
                                            r'before; \d+ messages since were lost'):
        for k in range(100, 5000):
            now[0] = k * 0.02
            writer.write(value, 10**9 + k * 10**7, raw)
    summary = writer.close()
    assert writer.closed and 50 <= summary.count < 5000
    with Reader(tmp_path / 'bag') as reader:
        assert reader.message_count == summary.count


def test_an_existing_output_is_refused_and_left_as_it_is(tmp_path):
    (tmp_path / 'old').mkdir()
    (tmp_path / 'old' / 'keep.txt').write_text('old bag')
    with pytest.raises(FileExistsError, match='exists already'):
        Sqlite3BagWriter(tmp_path / 'old')
    assert [p.name for p in (tmp_path / 'old').iterdir()] == ['keep.txt']
    assert (tmp_path / 'old' / 'keep.txt').read_text() == 'old bag'


def test_reindex_refuses_what_it_cannot_index(tmp_path):
    with pytest.raises(BagNotFoundError, match='no such bag folder'):
        reindex(tmp_path / 'missing')
    (tmp_path / 'empty').mkdir()
    with pytest.raises(BagNotFoundError, match='no .db3 storage file'):
        reindex(tmp_path / 'empty')
    write_bag(tmp_path / 'mcap', [Record(np.arange(1, 11) * 0.01, np.zeros(10), np.zeros(10),
                                         joint='j2')], storage='mcap')
    with pytest.raises(BagFormatError, match='sqlite3'):
        reindex(tmp_path / 'mcap')


@pytest.mark.skipif(not FIXTURES.is_dir(), reason=f'no rosbag2 fixtures at {FIXTURES}')
def test_reindex_the_split_bag_of_rosbag2s_own_reindex_test(tmp_path):
    source = FIXTURES / 'rosbag2_py/test/resources/sqlite3/reindex_test_bags/multiple_files'
    bag = tmp_path / 'multiple_files'
    bag.mkdir()
    for name in ('multiple_files_0.db3', 'multiple_files_1.db3', 'multiple_files_2.db3'):
        (bag / name).write_bytes((source / name).read_bytes())
    summary = reindex(bag)
    assert [f.path.name for f in summary.files] == ['multiple_files_0.db3',
                                                    'multiple_files_1.db3',
                                                    'multiple_files_2.db3']
    assert [f.count for f in summary.files] == [1324, 1324, 529]
    with Reader(bag) as reader:
        assert reader.message_count == 3177
        assert sum(1 for _ in reader.messages()) == 3177


def test_reindex_command(tmp_path, capsys):
    bag = _crashed_bag(tmp_path / 'bag')
    assert main(['reindex', str(bag), '--json']) == 0
    payload = json.loads(capsys.readouterr().out)
    assert payload['message_count'] == 401 and payload['metadata_version'] == 8
    assert payload['topics'] == [
        {'name': '/flag', 'type': 'std_msgs/msg/Bool', 'message_count': 201},
        {'name': '/value', 'type': 'std_msgs/msg/Float64', 'message_count': 200}]
    assert main(['reindex', str(bag)]) == 0
    out = capsys.readouterr().out
    assert out.startswith(f'wrote {bag / "metadata.yaml"}: 401 messages in 1 storage file(s)')
    assert summarise(bag).count == 401          # reindexing twice changes nothing
    assert main(['reindex', str(tmp_path / 'missing')]) == 2
    error = capsys.readouterr().err
    assert error == f'error: {tmp_path / "missing"}: no such bag folder\n'
    with pytest.raises(SystemExit):
        main(['reindex', '--help'])
    assert 'ros2 bag reindex' in capsys.readouterr().out

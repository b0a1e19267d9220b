"""
bag_recorder and bag_player as separate processes: a crash, an existing output, the end of a bag.

The plant publishes joint_states at 100 Hz; an outside node publishes a Bool and keeps its
own count of joint_states. The recorder is killed with SIGKILL; after ``hydro-sdp reindex``
the bag must hold everything up to the last commit, at most ``flush_period`` (1 s) before
the kill, each topic with its real type.
"""

import json
import os
import signal
import sqlite3
import subprocess
import time

from hydro_sdp.bags import read_bag, write_bag
from hydro_sdp.core.model.records import Record
import numpy as np
from outside import required_script
import pytest
import rclpy
from sensor_msgs.msg import JointState
from std_msgs.msg import Bool
from support.domains import fresh_domain

pytestmark = [pytest.mark.ros, pytest.mark.slow]

RATE = 100.0          # joint_states per second, the plant's default sample period 0.01 s
FLUSH = 1.0           # s, the recorder's default flush_period


class _Domain:
    """Processes and one outside node on a fresh ROS domain, discovery on this host only."""

    def __init__(self, monkeypatch):
        from rclpy.context import Context
        from rclpy.executors import SingleThreadedExecutor
        from rclpy.node import Node
        self.domain = fresh_domain()
        monkeypatch.setenv('ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST')
        self.environment = dict(os.environ, ROS_DOMAIN_ID=str(self.domain))
        self.processes = []
        self.context = Context()
        rclpy.init(context=self.context, domain_id=self.domain)
        self.node = Node('recorder_test', context=self.context)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)

    def start(self, name, *arguments):
        process = subprocess.Popen([required_script(name), '--ros-args', *arguments],
                                   env=self.environment, stdout=subprocess.DEVNULL,
                                   stderr=subprocess.PIPE, text=True)
        self.processes.append(process)
        return process

    def spin(self, seconds, until=lambda: False):
        end = time.monotonic() + seconds
        while time.monotonic() < end and not until():
            self.executor.spin_once(timeout_sec=0.01)
        return until()

    def close(self):
        for process in self.processes:
            if process.poll() is None:
                process.terminate()
        for process in self.processes:
            try:
                process.wait(timeout=10)
            except subprocess.TimeoutExpired:
                process.kill()
                process.wait(timeout=10)
        self.executor.shutdown()
        self.node.destroy_node()
        rclpy.try_shutdown(context=self.context)


@pytest.fixture
def domain(monkeypatch):
    ros = _Domain(monkeypatch)
    yield ros
    ros.close()


def _committed(db3, topic):
    """Messages of ``topic`` committed so far in a recorder's storage (read beside the writer)."""
    if not db3.is_file():
        return 0
    try:
        with sqlite3.connect(f'file:{db3}?mode=ro', uri=True, timeout=0.2) as connection:
            return connection.execute(
                'SELECT count(*) FROM messages JOIN topics ON topic_id = topics.id '
                'WHERE topics.name = ?', (topic,)).fetchone()[0]
    except sqlite3.OperationalError:     # the tables are being created, or locked
        return 0


def test_killed_recorder_keeps_all_but_the_last_second(domain, tmp_path):
    from rosbags.rosbag2 import Reader
    from rosbags.typesys import get_typestore, Stores

    received = []            # wall-clock receive times of joint_states at the outside node
    domain.node.create_subscription(JointState, 'joint_states',
                                    lambda m: received.append(time.time_ns()), 100)
    flag = domain.node.create_publisher(Bool, 'flag', 10)
    flags = []

    def publish_flag():
        flags.append(len(flags) % 3 == 0)
        flag.publish(Bool(data=flags[-1]))

    domain.node.create_timer(0.1, publish_flag)
    domain.start('plant_node', '-p', 'noise_std:=0.01')
    bag = tmp_path / 'run1'
    recorder = domain.start('bag_recorder', '-p', f'output:={bag}',
                            '-p', "topics:=['joint_states', 'flag']")
    db3 = bag / 'run1_0.db3'
    # Discovery in the recorder process takes its time: record from when both are in.
    assert domain.spin(60.0, lambda: _committed(db3, '/joint_states') > 0
                       and _committed(db3, '/flag') > 0), 'the recorder committed nothing'
    domain.spin(6.0)
    assert recorder.poll() is None, recorder.stderr.read()
    killed_at = time.time_ns()
    recorder.send_signal(signal.SIGKILL)
    recorder.wait(timeout=10)
    domain.spin(0.2)
    assert not (bag / 'metadata.yaml').exists()

    result = subprocess.run([required_script('hydro-sdp'), 'reindex', str(bag), '--json'],
                            capture_output=True, text=True, timeout=60)
    assert result.returncode == 0, result.stderr
    report = json.loads(result.stdout)
    assert (bag / 'metadata.yaml').is_file()

    typestore = get_typestore(Stores.ROS2_JAZZY)
    with Reader(bag) as reader:
        types = {c.topic: c.msgtype for c in reader.connections}
        assert types == {'/joint_states': 'sensor_msgs/msg/JointState',
                         '/flag': 'std_msgs/msg/Bool'}
        assert reader.message_count == report['message_count']
        flag_values = [typestore.deserialize_cdr(raw, c.msgtype).data
                       for c, _, raw in reader.messages() if c.topic == '/flag']
    # The Bools come back as Bools, with no gap: a slice of the publisher's pattern.
    assert len(flag_values) >= 30, (len(flag_values), len(flags))
    assert all(isinstance(v, bool) for v in flag_values), flag_values[:5]
    pattern = [k % 3 == 0 for k in range(len(flags) + 3)]
    offset = next(k for k in range(3) if pattern[k:k + 12] == flag_values[:12])
    assert flag_values == pattern[offset:offset + len(flag_values)]

    data = read_bag(bag)
    stamps = np.asarray(_receive_stamps(bag))
    first, last = stamps[0], stamps[-1]
    # Lost: at most the last flush period (and the time to run the commit).
    assert killed_at - last < (FLUSH + 0.3) * 1e9, (killed_at - last) / 1e9
    assert last - first > 5.0e9
    # Nothing missing before the last commit: as many as the outside node received then.
    window = sum(first <= t <= last for t in received)
    assert stamps.size >= 0.97 * window, (stamps.size, window)
    assert stamps.size >= 0.8 * RATE * (last - first) * 1e-9
    assert np.max(np.diff(stamps)) < 0.5e9
    assert data.t.size == stamps.size and data.names == ('j2',)


def _receive_stamps(bag):
    from rosbags.rosbag2 import Reader
    with Reader(bag) as reader:
        return [t for c, t, _ in reader.messages() if c.topic == '/joint_states']


def test_existing_output_is_refused_and_left_untouched(domain, tmp_path):
    old = tmp_path / 'old_bag'
    t = np.arange(1, 101) * 0.01
    write_bag(old, [Record(t, np.zeros(100), np.ones(100), joint='j2')])
    before = {p.name: p.read_bytes() for p in old.iterdir()}
    recorder = domain.start('bag_recorder', '-p', f'output:={old}')
    _, stderr = recorder.communicate(timeout=60)
    assert recorder.returncode == 2
    assert 'exists already' in stderr and str(old) in stderr
    assert 'Traceback' not in stderr
    assert {p.name: p.read_bytes() for p in old.iterdir()} == before


def test_player_exits_when_the_bag_is_played_unless_it_loops(domain, tmp_path):
    steps = 100                                   # 1 s of joint_states and valve commands
    t = np.arange(1, steps + 1) * 0.01
    write_bag(tmp_path / 'bag', [Record(t, np.zeros(steps), np.linspace(0, 10, steps),
                                        joint='j2')])
    received = []
    domain.node.create_subscription(JointState, 'joint_states', received.append, 100)
    # The player starts at once: give it a subscriber that is there before it.
    player = domain.start('bag_player', '-p', f'bag:={tmp_path / "bag"}', '-p', 'rate:=2.0')
    assert domain.spin(60.0, lambda: player.poll() is not None), 'the player did not exit'
    assert player.returncode == 0, player.stderr.read()
    assert f'played {2 * steps} messages' in player.stderr.read()

    received.clear()
    looping = domain.start('bag_player', '-p', f'bag:={tmp_path / "bag"}', '-p', 'rate:=4.0',
                           '-p', 'loop:=true')
    domain.spin(60.0, lambda: len(received) > 2.5 * steps or looping.poll() is not None)
    assert looping.poll() is None, looping.stderr.read()
    assert len(received) > 2.5 * steps              # played more than twice

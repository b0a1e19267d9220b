"""
The controller node on a faulty feedback link: drops, duplicates, delay bursts, restarts.

A simulated joint (the core JointSimulator) feeds the node's JointState callback through a
link that drops, duplicates and holds back messages; the node's clock is simulated time and
its watchdog timer runs on it. Each scenario is a 30 deg step that must settle without a
crash, without windup and, after the valve was closed, without a bump.
"""

import math
import os
from pathlib import Path
import shutil
import subprocess
import sys
import time

from hydro_sdp.core.model.simulation import JointSimulator
from hydro_sdp.io.model_files import default_model_path, load_model
from hydro_sdp.ros.controller_node import PipControllerNode
from hydro_sdp.ros.testing import RosHarness
import numpy as np
import pytest
import rclpy
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64
from support.domains import fresh_domain

pytestmark = pytest.mark.ros

PERIOD_NS = 10**7           # plant sample period, 0.01 s
STEP = 30.0                 # deg
STEPS = 800                 # 8 s


@pytest.fixture
def ros():
    """Return a harness with its own context, closed after the test."""
    with RosHarness() as harness:
        yield harness


class FaultyLoop:
    """A simulated joint and a controller node joined by a link that misbehaves."""

    def __init__(self, ros, seed=0):
        self.ros = ros
        self.model = load_model(default_model_path())
        self.plant = JointSimulator(self.model, PERIOD_NS * 1e-9, 0.0)
        self.rng = np.random.default_rng(seed)
        self.k = 0
        self.held = []
        self.angles, self.commands = [], []
        self.controller = self.start_controller()

    def start_controller(self):
        controller = self.ros.add(PipControllerNode)
        self.ros.set_time(max(self.k, 1) * PERIOD_NS)
        controller._on_setpoint(Float64(data=math.radians(STEP)))
        return controller

    def restart_controller(self):
        self.ros.executor.remove_node(self.controller)
        self.ros.nodes.remove(self.controller)
        self.controller.destroy_node()
        self.controller = self.start_controller()

    def _deliver(self, message):
        self.controller._on_state(message)

    def run(self, steps, *, drop=0.0, duplicate=0.0, hold=lambda k: False):
        for _ in range(steps):
            self.k += 1
            stamp = self.k * PERIOD_NS
            angle = self.plant.step(self.controller.last_command)
            self.ros.set_time(stamp)
            self.ros.executor.spin_once(timeout_sec=0.0)    # the watchdog runs on this time
            message = JointState()
            message.header.stamp.sec, message.header.stamp.nanosec = divmod(stamp, 10**9)
            message.name, message.position = ['j2'], [math.radians(angle)]
            if self.rng.random() < drop:
                pass
            elif hold(self.k):
                self.held.append(message)
            else:
                for late in self.held:
                    self._deliver(late)
                self.held = []
                self._deliver(message)
                if self.rng.random() < duplicate:
                    self._deliver(message)
            self.angles.append(angle)
            self.commands.append(self.controller.last_command)
        return np.array(self.angles), np.array(self.commands)


@pytest.fixture
def baseline(ros):
    return FaultyLoop(ros).run(STEPS)


def _assert_settled(angles, commands, baseline, overshoot=1.0):
    limits = load_model(default_model_path()).input_limits
    assert np.all(np.isfinite(commands))
    assert np.all((commands >= limits[0]) & (commands <= limits[1]))
    assert np.max(np.abs(angles[-200:] - STEP)) < 0.5                      # settled
    assert np.max(angles) < max(np.max(baseline[0]), STEP) + overshoot     # no windup


def test_fault_free_baseline_settles(baseline):
    angles, commands = baseline
    limits = load_model(default_model_path()).input_limits
    assert np.all((commands >= limits[0]) & (commands <= limits[1]))
    assert np.max(np.abs(angles[-200:] - STEP)) < 0.5
    # The closed-loop check's specification (docs/methods.md section 10): at most 10 %
    # overshoot; the scenarios below are then held against this baseline.
    assert np.max(angles) <= STEP * 1.10


def test_ten_percent_of_samples_dropped(ros, baseline):
    loop = FaultyLoop(ros, seed=1)
    angles, commands = loop.run(STEPS, drop=0.1)
    _assert_settled(angles, commands, baseline)
    assert loop.controller.refused == 0


def test_duplicated_samples_change_nothing(ros, baseline):
    loop = FaultyLoop(ros, seed=2)
    angles, commands = loop.run(STEPS, duplicate=0.1)
    np.testing.assert_array_equal(angles, baseline[0])
    np.testing.assert_array_equal(commands, baseline[1])
    assert loop.controller.refused > 50


def test_bursts_of_delay(ros, baseline):
    # Every 2 s the link holds 0.3 s of samples back, then releases them at once.
    loop = FaultyLoop(ros, seed=3)
    angles, commands = loop.run(STEPS, hold=lambda k: k % 200 >= 170)
    _assert_settled(angles, commands, baseline)


def test_blackout_closes_the_valve_and_control_resumes_without_a_bump(ros, baseline):
    loop = FaultyLoop(ros, seed=4)
    loop.run(60)                                   # 0.6 s in: valve wide open
    assert loop.controller.last_command > 1.0
    loop.run(100, hold=lambda k: True)             # 1 s without feedback
    assert loop.controller.gate.blind and loop.controller.last_command == 0.0
    refused = loop.controller.refused
    angles, commands = loop.run(STEPS - 160)       # the stale backlog is refused, then control
    assert loop.controller.refused > refused
    assert abs(loop.controller.controller.last_u) < 5.0
    _assert_settled(angles, commands, baseline)


def test_plant_restarted_mid_motion(ros, baseline):
    loop = FaultyLoop(ros, seed=5)
    loop.run(100)
    assert loop.angles[-1] > 15.0
    loop.plant = JointSimulator(loop.model, PERIOD_NS * 1e-9, 0.0)   # back at its start angle
    angles, commands = loop.run(STEPS)
    # The angle jump kicks the derivative-like feedback terms, so some overshoot follows;
    # the loop must stay stable and settle.
    _assert_settled(angles, commands, baseline, overshoot=8.0)


def test_controller_restarted_mid_motion(ros, baseline):
    loop = FaultyLoop(ros, seed=6)
    loop.run(60)
    loop.restart_controller()
    assert loop.controller.last_command == 0.0     # a new controller starts with the valve shut
    angles, commands = loop.run(STEPS - 60)
    _assert_settled(angles, commands, baseline)


def _script(name):
    return shutil.which(name, path=str(Path(sys.executable).parent))


class _Processes:
    """Node processes on one ROS domain, restartable by name."""

    def __init__(self, domain):
        self.environment = dict(os.environ, ROS_DOMAIN_ID=domain)
        self.running = {}
        self.finished = []

    def start(self, name, *arguments):
        self.running[name] = subprocess.Popen(
            [_script(name), '--ros-args', *arguments], env=self.environment,
            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)

    def stop(self, name):
        process = self.running.pop(name)
        assert process.poll() is None, f'{name} died: {process.stderr.read()}'
        process.terminate()
        try:
            process.wait(timeout=10)
        except subprocess.TimeoutExpired:
            # Rare with Fast DDS: a node that does not end on SIGTERM; this is about faults
            # while running, so end it and go on.
            process.kill()
            process.wait(timeout=10)
        self.finished.append((name, process))

    def stop_all(self):
        for name in list(self.running):
            self.stop(name)


@pytest.mark.slow
def test_separate_processes_survive_a_faulty_link_and_restarts(monkeypatch):
    """
    Plant and controller processes joined through a relay that drops, duplicates and blacks out.

    The plant publishes on ``raw/joint_states``; this test relays to ``joint_states`` with
    10 % dropped and 10 % duplicated, then a 1 s blackout, then restarts the controller and
    then the plant mid-motion. After each, the joint must settle on the set-point again, and
    every process must still be running when it is stopped. (What a process writes while it
    is being stopped is not checked here: SIGTERM racing a callback can end in a traceback.)
    """
    if _script('plant_node') is None:
        pytest.skip('the console scripts are not installed in this environment')
    from rclpy.context import Context
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.node import Node
    domain = str(fresh_domain())
    # The in-process harness turns discovery off; processes must find each other on the host.
    monkeypatch.setenv('ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST')
    processes = _Processes(domain)
    processes.start('plant_node', '-r', 'joint_states:=raw/joint_states', '-p', 'noise_std:=0.01')
    processes.start('controller_node')
    context = Context()
    rclpy.init(context=context, domain_id=int(domain))
    node = Node('faulty_link', context=context)
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(node)
    rng = np.random.default_rng(7)
    link = {'blackout': False}
    angles = []
    relay = node.create_publisher(JointState, 'joint_states', 10)
    setpoint = node.create_publisher(Float64, 'j2/setpoint', 10)

    def on_raw(message):
        angles.append((time.monotonic(), math.degrees(message.position[0])))
        if link['blackout'] or rng.random() < 0.1:
            return
        relay.publish(message)
        if rng.random() < 0.1:
            relay.publish(message)

    node.create_subscription(JointState, 'raw/joint_states', on_raw, 100)

    def spin(seconds):
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            executor.spin_once(timeout_sec=0.02)

    def command_step(degrees):
        deadline = time.monotonic() + 30.0
        while (setpoint.get_subscription_count() < 1 or not angles) and \
                time.monotonic() < deadline:
            executor.spin_once(timeout_sec=0.05)
        assert angles, 'no joint_states from the plant process'
        spin(0.5)
        setpoint.publish(Float64(data=math.radians(degrees)))

    def settled_on(degrees, deadline):
        # Process start-up and discovery take a varying time: wait for 1.5 s within 0.5 deg.
        # The set-point is said again every second: a restarted controller may subscribe
        # after the first one, while discovery still counts its predecessor's subscription.
        start = time.monotonic()
        while time.monotonic() < start + deadline:
            spin(0.25)
            now = time.monotonic()
            if int(now - start) != int(now - start - 0.25):
                setpoint.publish(Float64(data=math.radians(degrees)))
            window = [a for t, a in angles if t >= max(start, now - 1.5)]
            if now - start > 1.5 and len(window) > 100 and \
                    max(abs(a - degrees) for a in window) < 0.5:
                return True
        return False

    try:
        command_step(20.0)
        spin(0.6)
        link['blackout'] = True
        spin(1.0)
        link['blackout'] = False
        assert settled_on(20.0, 15.0), 'no settling after drops, duplicates and a blackout'
        command_step(-10.0)
        spin(0.6)                                   # mid-motion
        processes.stop('controller_node')
        processes.start('controller_node')
        command_step(-10.0)
        assert settled_on(-10.0, 15.0), 'no settling after the controller restarted'
        processes.stop('plant_node')                # back to its initial angle, 0 deg
        processes.start('plant_node', '-r', 'joint_states:=raw/joint_states',
                        '-p', 'noise_std:=0.01')
        assert settled_on(-10.0, 20.0), 'no settling after the plant restarted'
    finally:
        processes.stop_all()
        executor.shutdown()
        node.destroy_node()
        rclpy.try_shutdown(context=context)

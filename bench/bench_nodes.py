"""
Benchmark the ROS nodes.

Run with ``make bench`` or ``python bench/bench_nodes.py [--minutes 10]``. Prints:

* the in-process lockstep loop (plant, controller and identifier nodes, simulated
  time) against real time (target: at least 20x faster);
* one update of the online identifier, per sample (target: under 50 us);
* feedback-to-command latency of ``controller_node`` in its own process against a
  minimal rclpy echo node in its own process, measured in the same run (target:
  median at most 1.5x the echo's, p99 under 2 ms);
* a long run (default 10 minutes) of a 100 Hz ``plant_node`` and a 20 Hz
  ``controller_node`` in their own processes: missed control instants (target: none).

"""

import argparse
import math
import os
from pathlib import Path
import shutil
import subprocess
import sys
import tempfile
import time

from hydro_sdp.core.online import OnlineSdpIdentifier, OnlineSettings
from hydro_sdp.core.programs import random_program
from hydro_sdp.core.simulation import simulate
from hydro_sdp.files import default_model_path, load_model
import numpy as np

ECHO = """
import rclpy
from rclpy.node import Node
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64
rclpy.init()
node = Node('echo')
publisher = node.create_publisher(Float64, 'j2/valve_command', 10)
node.create_subscription(JointState, 'joint_states',
                         lambda message: publisher.publish(Float64(data=message.position[0])), 10)
try:
    rclpy.spin(node)
except KeyboardInterrupt:
    pass
"""


def lockstep_speed(steps: int) -> float:
    """Return simulated seconds per wall second of the three-node lockstep loop."""
    from hydro_sdp.ros.controller_node import PipControllerNode
    from hydro_sdp.ros.identifier_node import IdentifierNode
    from hydro_sdp.ros.plant_node import PlantNode
    from hydro_sdp.ros.testing import Lockstep, RosHarness
    with RosHarness() as ros:
        plant = ros.add(PlantNode, parameters={'noise_std': 0.02},
                        start_parameter_services=False)
        controller = ros.add(PipControllerNode)
        identifier = ros.add(IdentifierNode, start_parameter_services=False)
        loop = Lockstep(ros, plant, controllers=[controller], observers=[identifier])
        started = time.perf_counter()
        loop.run(steps)
        return steps * plant.sample_period / (time.perf_counter() - started)


def identifier_update() -> float:
    """Return microseconds per sample of the online identifier."""
    model = load_model(default_model_path())
    v = random_program(model, 0.01, 300.0, seed=1, y0=25.0)
    y = simulate(model, v, 0.01, 25.0) + np.random.default_rng(1).normal(0.0, 0.03, v.size)
    estimator = OnlineSdpIdentifier(model, 0.01, OnlineSettings(noise_std=0.03))
    pairs = list(zip(v.tolist(), y.tolist()))
    started = time.perf_counter()
    for command, angle in pairs:
        estimator.update(command, angle)
    return (time.perf_counter() - started) / len(pairs) * 1e6


def _context(domain: int):
    import rclpy
    from rclpy.context import Context
    # The in-process harness turned discovery off for this process; these nodes need the host.
    os.environ['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'
    context = Context()
    rclpy.init(context=context, domain_id=domain)
    return rclpy, context


def latency(command: list[str], domain: int, samples: int = 2000) -> np.ndarray:
    """Return publish-to-command latencies (s) of a node started by ``command``."""
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.node import Node
    from sensor_msgs.msg import JointState
    from std_msgs.msg import Float64
    environment = dict(os.environ, ROS_DOMAIN_ID=str(domain),
                       ROS_AUTOMATIC_DISCOVERY_RANGE='LOCALHOST')
    process = subprocess.Popen(command, env=environment, stdout=subprocess.DEVNULL,
                               stderr=subprocess.DEVNULL)
    rclpy, context = _context(domain)
    node = Node('latency_probe', context=context)
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(node)
    received = []
    node.create_subscription(Float64, 'j2/valve_command',
                             lambda message: received.append(time.perf_counter()), 100)
    publisher = node.create_publisher(JointState, 'joint_states', 10)
    try:
        deadline = time.monotonic() + 30.0
        while (publisher.get_subscription_count() < 1 or
               node.count_publishers('j2/valve_command') < 1) and time.monotonic() < deadline:
            executor.spin_once(timeout_sec=0.05)
        if publisher.get_subscription_count() < 1:
            raise RuntimeError(f'{command[0]} did not start or was not discovered')
        executor.spin_once(timeout_sec=1.0)
        delays = []
        stamp = 10**9
        for _ in range(samples):
            message = JointState()
            stamp += 50_000_000          # every sample is a control instant
            message.header.stamp.sec, message.header.stamp.nanosec = divmod(stamp, 10**9)
            message.name = ['j2']
            message.position = [math.radians(10.0)]
            count = len(received)
            sent = time.perf_counter()
            publisher.publish(message)
            while len(received) == count and time.perf_counter() - sent < 0.5:
                executor.spin_once(timeout_sec=0.0005)
            if len(received) > count:
                delays.append(received[-1] - sent)
            time.sleep(0.002)
        return np.array(delays)
    finally:
        process.terminate()
        process.wait(timeout=10)
        executor.shutdown()
        node.destroy_node()
        rclpy.try_shutdown(context=context)


def long_run(minutes: float, domain: int) -> tuple[int, int, int, float]:
    """Run plant (100 Hz) and controller (20 Hz) processes; count missed control instants."""
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.node import Node
    from sensor_msgs.msg import JointState
    from std_msgs.msg import Float64
    bin_dir = Path(sys.executable).parent
    environment = dict(os.environ, ROS_DOMAIN_ID=str(domain),
                       ROS_AUTOMATIC_DISCOVERY_RANGE='LOCALHOST')
    processes = [subprocess.Popen([str(bin_dir / name), '--ros-args'] + arguments,
                                  env=environment, stdout=subprocess.DEVNULL,
                                  stderr=subprocess.DEVNULL)
                 for name, arguments in (('plant_node', ['-p', 'noise_std:=0.02']),
                                         ('controller_node', []))]
    rclpy, context = _context(domain)
    node = Node('long_run_monitor', context=context)
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(node)
    commands, states = [], []
    node.create_subscription(Float64, 'j2/valve_command',
                             lambda message: commands.append(time.monotonic()), 100)
    node.create_subscription(JointState, 'joint_states',
                             lambda message: states.append(message.header.stamp.sec * 10**9 +
                                                           message.header.stamp.nanosec), 1000)
    setpoints = node.create_publisher(Float64, 'j2/setpoint', 10)
    try:
        deadline = time.monotonic() + 30.0
        while not commands and time.monotonic() < deadline:
            executor.spin_once(timeout_sec=0.05)
        started = time.monotonic()
        first_state = len(states)
        first_command = len(commands)
        level = 0
        while time.monotonic() - started < minutes * 60.0:
            if time.monotonic() - started > 5.0 * level:
                setpoints.publish(Float64(data=math.radians(20.0 if level % 2 else 40.0)))
                level += 1
            executor.spin_once(timeout_sec=0.01)
        ticks = len(states) - first_state
        sent = len(commands) - first_command
        # Control instants: one every 5 plant samples; a missed one leaves a gap of two or more.
        gaps = np.diff(np.array(commands[first_command:]))
        return ticks, sent, int(np.sum(gaps > 0.075)), float(np.max(gaps))
    finally:
        for process in processes:
            process.terminate()
        for process in processes:
            process.wait(timeout=10)
        executor.shutdown()
        node.destroy_node()
        rclpy.try_shutdown(context=context)


def main():
    """Run the benchmarks and print the figures."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('--minutes', type=float, default=10.0,
                        help='length of the long run (default: 10)')
    args = parser.parse_args()
    speed = lockstep_speed(3000)
    print(f'in-process lockstep loop (plant 100 Hz, controller, identifier): '
          f'{speed:.1f}x real time (target >= 20x)')
    print(f'online identifier update: {identifier_update():.1f} us per sample (target < 50 us)')
    controller_script = shutil.which('controller_node', path=str(Path(sys.executable).parent))
    if controller_script is None:
        print('console scripts not installed: skipping the process benchmarks')
        return
    domain = 150 + os.getpid() % 50
    with tempfile.TemporaryDirectory():
        # The probe's stamps run 20x faster than the wall clock; on simulated time that never
        # starts, the controller takes them without comparing them with its clock.
        ours = latency([controller_script, '--ros-args', '-p', 'control_period:=0.05',
                        '-p', 'use_sim_time:=true'], domain)
        echo = latency([sys.executable, '-c', ECHO], domain + 1)
    print('feedback-to-command latency, each node in its own process '
          f'({ours.size} and {echo.size} samples):')
    for name, values in (('controller_node', ours), ('rclpy echo node', echo)):
        print(f'  {name:16s} median {1e3 * np.median(values):6.3f} ms, '
              f'p99 {1e3 * np.percentile(values, 99):6.3f} ms')
    print(f'  ratio of medians: {np.median(ours) / np.median(echo):.2f} (target <= 1.5); '
          f'p99 target < 2 ms')
    ticks, sent, missed, worst = long_run(args.minutes, domain + 2)
    print(f'{args.minutes:g}-minute run, plant 100 Hz and controller 20 Hz in their own '
          f'processes: {ticks} plant samples, {sent} commands, {missed} missed control '
          f'instants (largest gap {1e3 * worst:.1f} ms; target: none missed)')


if __name__ == '__main__':
    main()

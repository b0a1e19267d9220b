"""
Node processes timed from outside: feedback-to-command latency, start-up, a long run.

Used by ``bench_nodes.py``: :func:`process_rounds` runs a raw rclpy echo node,
``controller_node`` and ``plant_node`` alternately, each in a fresh ``ROS_DOMAIN_ID``, and
times them from a probe node in this process; :func:`long_run` counts missed control instants
of a plant and a controller process.

"""

import math
import os
from pathlib import Path
import subprocess
import sys
import time
from typing import Any, NamedTuple

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
# Fast DDS maps a domain to UDP ports; domains up to 232 are usable.
FIRST_DOMAIN, LAST_DOMAIN = 120, 232


def _context(domain: int) -> tuple[Any, Any]:
    import rclpy
    from rclpy.context import Context
    # The in-process harness turned discovery off for this process; these nodes need the host.
    os.environ['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'
    context = Context()
    rclpy.init(context=context, domain_id=domain)
    return rclpy, context


class Run(NamedTuple):
    """One process measured: start-up (s) and publish-to-command latencies (s)."""

    startup: float
    latencies: np.ndarray


def _stop(process: subprocess.Popen) -> None:
    process.terminate()
    try:
        process.wait(timeout=10)
    except subprocess.TimeoutExpired:
        process.kill()
        process.wait()


def joint_state(stamp_ns: int) -> Any:
    """Return a JointState of joint ``j2`` at 10 deg, stamped ``stamp_ns``."""
    from sensor_msgs.msg import JointState
    message = JointState()
    message.header.stamp.sec, message.header.stamp.nanosec = divmod(stamp_ns, 10**9)
    message.name = ['j2']
    message.position = [math.radians(10.0)]
    return message


def measure(command: list[str], domain: int, samples: int, *, output: str = 'j2/valve_command',
            feed: bool = True, settle: float = 0.0, timeout: float = 60.0) -> Run:
    """
    Spawn ``command`` in ``domain`` and time its start-up and, if ``feed``, its latency.

    The probe node is ready (subscribed, publishing) before the process is spawned.
    Start-up is the time from the spawn to the first message on ``output``; with
    ``feed`` the probe publishes a JointState every 5 ms meanwhile. Latency is then
    the time from publishing one JointState to receiving the command it caused
    (``samples`` of them after 20 not counted), taken ``settle`` seconds after the
    first message; stamps advance 50 ms a message, so every sample is a control
    instant of a 20 Hz controller.
    """
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.node import Node
    from sensor_msgs.msg import JointState
    from std_msgs.msg import Float64
    environment = dict(os.environ, ROS_DOMAIN_ID=str(domain),
                       ROS_AUTOMATIC_DISCOVERY_RANGE='LOCALHOST')
    rclpy, context = _context(domain)
    node = Node('latency_probe', context=context)
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(node)
    received: list[float] = []
    output_type = Float64 if output.endswith('valve_command') else JointState
    node.create_subscription(output_type, output,
                             lambda message: received.append(time.perf_counter()), 100)
    publisher = node.create_publisher(JointState, 'joint_states', 10)
    stamp = 10**9
    process = None
    try:
        started = time.perf_counter()
        process = subprocess.Popen(command, env=environment, stdout=subprocess.DEVNULL,
                                   stderr=subprocess.DEVNULL)
        fed = started
        while not received and time.perf_counter() - started < timeout:
            if feed and time.perf_counter() - fed >= 0.005:
                stamp += 50_000_000
                publisher.publish(joint_state(stamp))
                fed = time.perf_counter()
            executor.spin_once(timeout_sec=0.001)
        if not received:
            raise RuntimeError(f'{command[0]} sent nothing on {output} in {timeout:g} s')
        startup = received[0] - started
        settled = time.perf_counter()
        while time.perf_counter() - settled < settle:
            executor.spin_once(timeout_sec=0.01)
        delays = []
        for index in range(samples + 20 if feed else 0):
            stamp += 50_000_000
            message = joint_state(stamp)
            count = len(received)
            sent = time.perf_counter()
            publisher.publish(message)
            while len(received) == count and time.perf_counter() - sent < 0.5:
                executor.spin_once(timeout_sec=0.0005)
            if len(received) > count and index >= 20:
                delays.append(received[-1] - sent)
            time.sleep(0.002)
        return Run(startup, np.array(delays))
    finally:
        if process is not None:
            _stop(process)
        executor.shutdown()
        node.destroy_node()
        rclpy.try_shutdown(context=context)


def _range(values: list[float], scale: float = 1.0, digits: int = 3) -> str:
    scaled = np.asarray(values) * scale
    return f'[{np.min(scaled):.{digits}f}..{np.max(scaled):.{digits}f}]'


def _spread(values: list[float], scale: float = 1.0, digits: int = 3) -> str:
    return f'{np.median(values) * scale:.{digits}f} {_range(values, scale, digits)}'


def process_rounds(rounds: int, samples: int, settle: float = 0.0) -> dict[str, list[Run]]:
    """
    Measure the echo node, ``controller_node`` and ``plant_node`` alternately.

    Each run gets a fresh ``ROS_DOMAIN_ID``; the order of the three turns every round,
    so no node is always the first after a quiet spell.
    """
    bin_dir = Path(sys.executable).parent
    commands = {
        'echo': ([sys.executable, '-c', ECHO], True, 'j2/valve_command'),
        # The probe's stamps run 20x faster than the wall clock; on simulated time that
        # never starts, the controller takes them without comparing them with its clock.
        'controller': ([str(bin_dir / 'controller_node'), '--ros-args',
                        '-p', 'control_period:=0.05', '-p', 'use_sim_time:=true'],
                       True, 'j2/valve_command'),
        'plant': ([str(bin_dir / 'plant_node')], False, 'joint_states'),
    }
    order = list(commands)
    span = LAST_DOMAIN - FIRST_DOMAIN + 1
    domain = FIRST_DOMAIN + (os.getpid() * 7) % (span - 1)
    runs: dict[str, list[Run]] = {name: [] for name in order}
    # Not counted: the probe's first DDS participant and a cold file cache.
    measure(commands['echo'][0], domain, 20)
    domain += 1
    for index in range(rounds):
        for name in order[index % 3:] + order[:index % 3]:
            command, feed, output = commands[name]
            runs[name].append(measure(command, domain, samples, output=output, feed=feed,
                                      settle=settle))
            domain = FIRST_DOMAIN + (domain - FIRST_DOMAIN + 1) % span
    return runs


def report_processes(runs: dict[str, list[Run]]) -> None:
    """Print latency and start-up figures, with the spread over rounds, and both ratios."""
    echo, ours, plant = runs['echo'], runs['controller'], runs['plant']
    rounds = len(echo)
    print(f'feedback-to-command latency, each node in its own process, {rounds} rounds '
          f'alternating, fresh ROS_DOMAIN_ID per run, {echo[0].latencies.size} samples a run; '
          'median of all samples [round medians min..max], ms:')
    for name, these in (('rclpy echo node', echo), ('controller_node', ours)):
        pooled = np.concatenate([run.latencies for run in these])
        print(f'  {name:16s} median {1e3 * np.median(pooled):6.3f} '
              f'{_range([np.median(r.latencies) for r in these], 1e3)}, '
              f'p99 {1e3 * np.percentile(pooled, 99):6.3f}')
    ratio = (np.median(np.concatenate([r.latencies for r in ours])) /
             np.median(np.concatenate([r.latencies for r in echo])))
    per_round = [np.median(o.latencies) / np.median(e.latencies) for o, e in zip(ours, echo)]
    print(f'  latency ratio controller/echo (medians): {ratio:.2f}; per round '
          f'{_spread(per_round, digits=2)} (target <= 1.2; p99 target < 2 ms)')
    print('start-up, spawn to first message, median [min..max] of the rounds, s:')
    for name, these in (('rclpy echo node (first output, fed joint_states)', echo),
                        ('controller_node (first valve_command, fed joint_states)', ours),
                        ('plant_node (first joint_states)', plant)):
        print(f'  {name:56s} {_spread([r.startup for r in these])}')
    for name, these in (('controller/echo', ours), ('plant/echo', plant)):
        paired = [run.startup / base.startup for run, base in zip(these, echo)]
        print(f'  start-up ratio {name}: '
              f'{np.median([r.startup for r in these]) / np.median([r.startup for r in echo]):.2f}'
              f' (medians); per round {_spread(paired, digits=2)}')


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
    commands: list[float] = []
    states: list[int] = []

    def on_state(message: Any) -> None:
        states.append(message.header.stamp.sec * 10**9 + message.header.stamp.nanosec)

    node.create_subscription(Float64, 'j2/valve_command',
                             lambda message: commands.append(time.monotonic()), 100)
    node.create_subscription(JointState, 'joint_states', on_state, 1000)
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

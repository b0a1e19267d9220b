"""
Benchmark the ROS nodes.

Run with ``make bench`` or ``python bench/bench_nodes.py [--rounds 5] [--minutes 10]``.
Prints:

* the in-process lockstep loop (plant, controller and identifier nodes, simulated
  time) against real time (target: at least 20x faster);
* one update of the online identifier, per sample, against a plain numpy Kalman step
  of the same six states measured in the same run (target: under 10 us; the update,
  written out on Python floats, takes about half the plain step's time): eq. (5)'s
  filter, and the edges' filter of any other family on the same J2 samples (methods.md
  section 7.6);
* the controller node's ``joint_states`` callback in-process, per control sample, with the
  PIP-IDZ step alone and a raw echo callback beside it (:func:`callback_costs`);
* feedback-to-command latency of ``controller_node`` in its own process against a
  minimal rclpy echo node (JointState in, Float64 out) in its own process, measured by
  this process as an outside client: the two run alternately, each run in a fresh
  ``ROS_DOMAIN_ID``, for several rounds; medians and p99 of each, and the ratio of
  the medians (target: at most 1.2, p99 under 2 ms), from ``--settle`` seconds (3)
  after each node's first message;
* start-up, from spawning the process to its first message (measured the same way in
  the same rounds): ``plant_node`` to its first ``joint_states``, ``controller_node``
  (fed ``joint_states``) to its first ``valve_command``, and the echo node (fed the
  same) to its first output; the ratios to the echo node's;
* a long run (default 10 minutes) of a 100 Hz ``plant_node`` and a 20 Hz
  ``controller_node`` in their own processes: missed control instants (target: none).

"""

import argparse
import os
from pathlib import Path
import shutil
import sys
import time
from typing import Any

from hydro_sdp.core.identification.online import OnlineSdpIdentifier, OnlineSettings
from hydro_sdp.core.identification.online_edges import OnlineEdgeIdentifier
from hydro_sdp.core.model.simulation import simulate
from hydro_sdp.core.synthetic.programs import random_program
from hydro_sdp.io.model_files import default_model_path, load_model
from node_processes import long_run, process_rounds, report_processes
import numpy as np


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


def identifier_update(edges: bool = False) -> float:
    """Return microseconds per sample of the online identifier (``edges``: the edges' filter)."""
    model = load_model(default_model_path())
    v = random_program(model, 0.01, 300.0, seed=1, y0=25.0)
    y = simulate(model, v, 0.01, 25.0) + np.random.default_rng(1).normal(0.0, 0.03, v.size)
    kind = OnlineEdgeIdentifier if edges else OnlineSdpIdentifier
    estimator = kind(model, 0.01, OnlineSettings(noise_std=0.03))
    pairs = list(zip(v.tolist(), y.tolist()))
    started = time.perf_counter()
    for command, angle in pairs:
        estimator.update(command, angle)
    return (time.perf_counter() - started) / len(pairs) * 1e6


def plain_kalman_step() -> float:
    """
    Return microseconds per sample of a textbook random-walk Kalman filter in numpy.

    The baseline of :func:`identifier_update`: the same six states and one measurement
    per sample, written as the equations read (``P + Q``, ``P psi``, ``S``, the gain,
    ``theta`` and ``P`` updated with ``np.outer``), with none of the identifier's gating,
    change detection or soft-edged gradient.
    """
    rng = np.random.default_rng(1)
    regressors = rng.normal(size=(30_000, 6))
    measured = regressors @ np.arange(1.0, 7.0) + rng.normal(0.0, 0.1, regressors.shape[0])
    theta, P, Q, r = np.zeros(6), np.eye(6), 1e-6 * np.eye(6), 0.01
    rows = list(zip(regressors, measured.tolist()))
    started = time.perf_counter()
    for psi, z in rows:
        P = P + Q
        Ppsi = P @ psi
        S = r + float(psi @ Ppsi)
        gain = Ppsi / S
        theta = theta + gain * (z - float(psi @ theta))
        P = P - np.outer(gain, Ppsi)
    return (time.perf_counter() - started) / len(rows) * 1e6


def callback_costs(messages: int = 20000) -> tuple[float, float, float]:
    """
    Return microseconds per JointState of three callbacks in-process, each the median of 5 runs.

    The controller node's ``joint_states`` callback for samples that are all control
    instants (conversion, clock, gate, schedule, the PIP-IDZ step, publishing the command
    and the bookkeeping after it, with nobody listening to ``controller_state``), the
    PIP-IDZ step alone (the core object), and a raw echo callback (a Float64 built from the
    position and published); publishers without subscribers, no DDS transport.
    """
    from hydro_sdp.core.control.controller_spec import design_from_model
    from hydro_sdp.core.control.pip_controller import PipIdzController
    from hydro_sdp.ros.controller_node import PipControllerNode
    from hydro_sdp.ros.testing import RosHarness
    from node_processes import joint_state
    from std_msgs.msg import Float64

    def median_of_runs(call: Any, argument: list[Any]) -> float:
        runs = []
        for _ in range(5):
            started = time.perf_counter()
            for item in argument:
                call(item)
            runs.append((time.perf_counter() - started) / len(argument) * 1e6)
        return float(np.median(runs))

    with RosHarness() as ros:
        # Simulated time that never starts: stamps are taken without a freshness check.
        controller = ros.add(PipControllerNode)
        echo = ros.helper('echo')
        publisher = echo.create_publisher(Float64, 'echo', 10)
        states = [joint_state(10**9 + k * 50_000_000) for k in range(5 * messages)]
        feed = iter(states)
        node = median_of_runs(lambda _: controller._on_state(next(feed)), [None] * messages)
        assert controller.outputs == 5 * messages, 'every sample must be a control instant'
        echoed = median_of_runs(
            lambda m: publisher.publish(Float64(data=m.position[0])), states[:messages])
    model = load_model(default_model_path())
    pip = PipIdzController(design_from_model(model).settings())
    step = median_of_runs(lambda k: pip.step(20.0, 0.01 * (k % 100)), list(range(messages)))
    return node, step, echoed


def main() -> None:
    """Run the benchmarks and print the figures."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('--rounds', type=int, default=5,
                        help='rounds of the alternating process runs (default: 5)')
    parser.add_argument('--samples', type=int, default=500,
                        help='latency samples per process run (default: 500)')
    parser.add_argument('--settle', type=float, default=3.0,
                        help='seconds between the first message of a node and the latency '
                             'samples (default: 3, once discovery and the start-up are over; '
                             '0 measures right after start-up)')
    parser.add_argument('--minutes', type=float, default=10.0,
                        help='length of the long run (default: 10; 0 skips it)')
    parser.add_argument('--processes-only', action='store_true',
                        help='skip the in-process figures')
    args = parser.parse_args()
    if not args.processes_only:
        speed = lockstep_speed(3000)
        print(f'in-process lockstep loop (plant 100 Hz, controller, identifier): '
              f'{speed:.1f}x real time (target >= 20x)')
        update, plain = identifier_update(), plain_kalman_step()
        edges = identifier_update(edges=True)
        print(f'online identifier update: {update:.1f} us per sample against {plain:.1f} us '
              f'for a plain numpy Kalman step of the same size: x{update / plain:.2f} '
              f"(target < 10 us); the edges' filter of any family {edges:.1f} us: "
              f'x{edges / plain:.2f}')
        node, step, echoed = callback_costs()
        print(f'controller_node joint_states callback, in-process, per control sample: '
              f'{node:.1f} us (of which the PIP-IDZ step {step:.1f} us) against {echoed:.1f} us '
              f'for a raw echo callback: x{node / echoed:.2f}')
    if shutil.which('controller_node', path=str(Path(sys.executable).parent)) is None:
        print('console scripts not installed: skipping the process benchmarks')
        return
    report_processes(process_rounds(args.rounds, args.samples, args.settle))
    if args.minutes > 0:
        ticks, sent, missed, worst = long_run(args.minutes, 100 + os.getpid() % 20)
        print(f'{args.minutes:g}-minute run, plant 100 Hz and controller 20 Hz in their own '
              f'processes: {ticks} plant samples, {sent} commands, {missed} missed control '
              f'instants (largest gap {1e3 * worst:.1f} ms; target: none missed)')


if __name__ == '__main__':
    main()

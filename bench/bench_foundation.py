"""
Benchmark the foundation: simulation speed and bag reading, each against a baseline.

Run with ``make bench`` or ``python bench/bench_foundation.py``. Prints, from
one run on this machine:

* samples per second of :func:`hydro_sdp.core.model.simulation.simulate` on the J2
  ``sdp`` model with end stops, against a plain per-sample Python loop of the
  same equations (target: at least 20x faster);
* seconds to read a one-hour 100 Hz bag (JointState + Float64, 720,000
  messages) into a record with :func:`hydro_sdp.bags.read_bag`, against
  rosbags' own per-message deserialisation of the same bag (target: no slower).

"""

import argparse
import math
from pathlib import Path
import sys
import tempfile
import time

from hydro_sdp.bags import read_bag, write_bag
from hydro_sdp.core.model.records import Record
from hydro_sdp.core.model.simulation import JointSimulator, simulate
from hydro_sdp.core.synthetic.programs import random_program
from hydro_sdp.io.model_files import default_model_path, load_model
import numpy as np

# The plain loop is the test suite's reference of the paper's recursion.
sys.path.insert(0, str(Path(__file__).resolve().parent.parent / 'test'))
from support.paper_recursion import paper_recursion  # noqa: E402, I100


def best_of(repeats, function):
    """Return the shortest wall time of ``repeats`` calls and the last result."""
    best = math.inf
    result = None
    for _ in range(repeats):
        start = time.perf_counter()
        result = function()
        best = min(best, time.perf_counter() - start)
    return best, result


def rosbags_baseline(path, joint, topic):
    """Read the bag with rosbags' per-message deserialisation, then align as hydro_sdp does."""
    from rosbags.rosbag2 import Reader
    from rosbags.typesys import get_typestore, Stores

    typestore = get_typestore(Stores.ROS2_JAZZY)
    stamps, angles, command_t, command = [], [], [], []
    with Reader(path) as reader:
        for connection, timestamp, raw in reader.messages():
            message = typestore.deserialize_cdr(raw, connection.msgtype)
            if connection.topic == '/joint_states':
                stamps.append(message.header.stamp.sec * 10**9 + message.header.stamp.nanosec)
                angles.append(message.position[list(message.name).index(joint)])
            elif connection.topic == topic:
                command_t.append(timestamp)
                command.append(message.data)
    t = np.asarray(stamps) * 1e-9
    index = np.searchsorted(np.asarray(command_t) * 1e-9, t, side='left') - 1
    keep = index >= 0
    return Record(t[keep], np.asarray(command)[index[keep]], np.degrees(np.asarray(angles))[keep],
                  joint=joint)


def main():
    """Run the benchmarks and print the figures."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('--hours', type=float, default=1.0, help='bag length (default: 1 h)')
    args = parser.parse_args()
    model = load_model(default_model_path())
    rng = np.random.default_rng(1)
    samples = int(round(args.hours * 3600 * 100))
    # Random levels without sign control, so the joint runs into both end stops often.
    v = np.repeat(rng.uniform(-6.0, 6.0, samples // 150 + 1), 150)[:samples]
    print(f'simulation of {samples:,} samples (J2 sdp model, end stops, 100 Hz)')
    fast, y = best_of(3, lambda: simulate(model, v, 0.01, 25.0))
    slow, reference = best_of(1, lambda: paper_recursion(model.alpha(0.01), 15, v, 25.0,
                                                         *model.angle_limits))
    stepper = JointSimulator(model, 0.01, 25.0)
    stepped, _ = best_of(1, lambda: [stepper.step(x) for x in v[:50_000].tolist()])
    error = float(np.max(np.abs(y - np.asarray(reference))))
    at_stops = float(np.mean((y == model.angle_limits[0]) | (y == model.angle_limits[1])))
    print(f'  simulate (numpy):        {samples / fast:14,.0f} samples/s')
    print(f'  plain Python loop:       {samples / slow:14,.0f} samples/s')
    print(f'  JointSimulator.step:     {50_000 / stepped:14,.0f} samples/s (one at a time)')
    print(f'  speed-up: {slow / fast:.1f}x (target >= 20x); max difference {error:.1e} deg; '
          f'{100 * at_stops:.0f} % of samples at an end stop')
    evaluation = random_program(model, 0.01, samples * 0.01, seed=2, y0=25.0)
    fast_eval, _ = best_of(3, lambda: simulate(model, evaluation, 0.01, 25.0))
    slow_eval, _ = best_of(1, lambda: paper_recursion(model.alpha(0.01), 15, evaluation,
                                                      25.0, *model.angle_limits))
    print(f'  random program (evaluation runs): {samples / fast_eval:,.0f} against '
          f'{samples / slow_eval:,.0f} samples/s, {slow_eval / fast_eval:.1f}x')

    with tempfile.TemporaryDirectory() as folder:
        t = np.arange(1, samples + 1) * 0.01
        record = Record(t, v, y, joint='j2')
        for storage in ('sqlite3', 'mcap'):
            bag = Path(folder) / f'hour_{storage}'
            written, _ = best_of(1, lambda: write_bag(bag, [record], storage=storage))
            ours, back = best_of(1, lambda: read_bag(bag).record('j2'))
            theirs, baseline = best_of(1, lambda: rosbags_baseline(bag, 'j2',
                                                                   '/j2/valve_command'))
            assert np.array_equal(back.v, baseline.v) and np.allclose(back.y, baseline.y)
            print(f'bag of {2 * samples:,} messages ({storage}), written in {written:.1f} s')
            print(f'  hydro_sdp read_bag + record:  {ours:6.2f} s')
            print(f'  rosbags deserialise_cdr:      {theirs:6.2f} s')
            print(f'  speed-up: {theirs / ours:.1f}x (target >= 1x)')


if __name__ == '__main__':
    main()

"""
Benchmark a simulation's step on a ``power_sat`` joint: one command's speed in floats.

Run with ``make bench`` or ``python bench/bench_power_sat_step.py``. Steps the shipped
physics arm's model (``config/physics_arm_model.yaml``, kind ``power_sat``) through a
closed-loop-like program of commands, as the closed-loop checks of calibrate do, and
prints the time per step against the old path timed in the same run: the map evaluated
by numpy on a one-element array. Both give the same angles, bit for bit.

"""

from pathlib import Path
import time

from hydro_sdp.core.model import simulation
from hydro_sdp.core.model.static_maps import power_sat
from hydro_sdp.io.model_files import load_model
import numpy as np

CONFIG = Path(__file__).resolve().parent.parent / 'config'


def run(model, commands):
    """Step a simulator through ``commands``; return its angles and the seconds it took."""
    start = time.perf_counter()
    sim = simulation.JointSimulator(model, 0.01, 10.0)
    angles = [sim.step(v) for v in commands]
    return np.array(angles), time.perf_counter() - start


def main():
    """Run the benchmark and print the figures."""
    model = load_model(CONFIG / 'physics_arm_model.yaml')
    rng = np.random.default_rng(1)
    commands = np.repeat(rng.uniform(-100.0, 100.0, 400), 50).tolist()
    fast, slow = [], []
    one_rate = power_sat._one_rate
    for _ in range(3):
        fast_angles, seconds = run(model, commands)
        fast.append(seconds)
        power_sat._one_rate = lambda *arguments: None     # the old path: numpy on [v]
        try:
            slow_angles, seconds = run(model, commands)
        finally:
            power_sat._one_rate = one_rate
        slow.append(seconds)
        assert np.array_equal(fast_angles, slow_angles)
    per_step = 1e6 / len(commands)
    print(f'one simulation step, power_sat joint ({len(commands)} steps, best of 3)')
    print(f'  one command in floats:  {min(fast) * per_step:6.2f} us')
    print(f'  numpy on [v] (old):     {min(slow) * per_step:6.2f} us  '
          f'({min(slow) / min(fast):.2f}x the new)')


if __name__ == '__main__':
    main()

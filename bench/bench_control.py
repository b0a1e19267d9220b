"""
Benchmark one step of the runtime PIP-IDZ controller.

Run with ``make bench`` or ``python bench/bench_control.py``. Prints the time of
one :meth:`PipIdzController.step` (incremental PIP + inverse dead-zone + limits,
J2 design) in microseconds (target: under 20 us), against two baselines timed
in the same run: the bare eq. (8) arithmetic in a Python function, and an empty
Python method call (the floor any Python controller pays).

"""

import timeit

from hydro_sdp.core.control.controller_spec import design_from_model
from hydro_sdp.io.model_files import default_model_path, load_model
import numpy as np


class _Empty:
    def step(self, setpoint, y):
        return setpoint, y


def _bare_eq8(state, setpoint, y, f0=0.1261, g1=0.12, g2=0.1261, k_i=0.0061):
    u1, u2, u3, y1 = state
    u = u1 - g1 * (u1 - u2) - g2 * (u2 - u3) - f0 * (y - y1) + k_i * (setpoint - y)
    state[:] = [u, u1, u2, y]
    return u


def per_call(function, number=200_000, repeat=5):
    """Return the best time of one call, in microseconds."""
    return min(timeit.repeat(function, number=number, repeat=repeat)) / number * 1e6


def main():
    """Run the benchmark and print the figures."""
    spec = design_from_model(load_model(default_model_path()))
    controller = spec.controller()
    angles = iter(np.tile(np.linspace(-5.0, 25.0, 1000), 10_000).tolist())
    ours = per_call(lambda: controller.step(20.0, next(angles)))
    state = [0.0, 0.0, 0.0, 0.0]
    bare = per_call(lambda: _bare_eq8(state, 20.0, 1.0))
    empty = _Empty()
    floor = per_call(lambda: empty.step(20.0, 1.0))
    print('one control step (PIP + IDZ + limits, J2 design)')
    print(f'  PipIdzController.step:  {ours:6.2f} us  (target < 20 us)')
    print(f'  bare eq. (8) function:  {bare:6.2f} us  ({ours / bare:.1f}x)')
    print(f'  empty method call:      {floor:6.2f} us  ({ours / floor:.1f}x)')


if __name__ == '__main__':
    main()

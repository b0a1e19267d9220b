"""
Benchmark the link's mode over a run: modal coordinates in closed form against eig and inv.

Run with ``python bench/bench_link_mode.py``. The oscillation detector's fit filters every
record through hundreds of trial modes (``LinkMode.states``); each call formed the 2 x 2
modal decomposition with ``numpy.linalg.eig`` and ``inv``, now in closed form
(``LinkMode.modal``). Prints the time per call of both on the same 30 s run and trial
modes, and the largest difference of their deviations.

"""

import time

from hydro_sdp.core.model.effects import Oscillation
from hydro_sdp.core.model.link_mode import LinkMode
import numpy as np
from scipy.signal import lfilter

CALLS = 2000


def through_eig(mode, speeds, before):
    """Return the deviations as the modal form with numpy's eig and inv gave them."""
    p00, p01, p10, p11 = mode.transition
    poles, vectors = np.linalg.eig(np.array([[p00, p01], [p10, p11]]))
    pole, inverse = complex(poles[0]), np.linalg.inv(vectors)
    gain = complex(inverse[0] @ np.array(mode.input_gain))
    state = complex(inverse[0] @ np.array(mode.settled(before)))
    out = lfilter([gain], [1.0, -pole], speeds.astype(np.complex128), zi=[pole * state])[0]
    return 2.0 * (complex(vectors[0, 0]) * out).real


def main():
    """Time both forms over the same trial modes."""
    speeds = np.random.default_rng(1).normal(0.0, 5.0, 3000)
    modes = [LinkMode.of(Oscillation(1.0 + 0.002 * k, 0.05 + 1e-4 * k), 0.01)
             for k in range(CALLS)]
    times, results = {}, {}
    for name, form in (('eig and inv', through_eig),
                       ('closed form', lambda m, w, b: m.states(w, b)[0])):
        start = time.perf_counter()
        results[name] = [form(mode, speeds, 2.0) for mode in modes]
        times[name] = (time.perf_counter() - start) / CALLS
    gap = max(float(np.max(np.abs(a - b))) for a, b in zip(*results.values()))
    print(f'per call: eig and inv {1e6 * times["eig and inv"]:.0f} us, closed form '
          f'{1e6 * times["closed form"]:.0f} us, ratio '
          f'{times["eig and inv"] / times["closed form"]:.2f}x; largest difference {gap:.2g} deg')


if __name__ == '__main__':
    main()

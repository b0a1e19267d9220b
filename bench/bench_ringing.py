"""
Benchmark the link's increments at the stops: stretches at once against sample by sample.

Run with ``python bench/bench_ringing.py``. The oscillation detector's fit predicts every
record through hundreds of trial modes; once a record meets a stop, the prediction stepped
each remaining sample in Python. It now follows each stretch between the meetings at once
(``simulation._ringing_increments``, methods 3.6). Prints the time per record of both on the
same records (strokes pressing both stops many times) and trial modes, and the largest
difference of their increments.

"""

from pathlib import Path
import sys
import time

from hydro_sdp.core.model.effects import Oscillation
from hydro_sdp.core.model.link_mode import LinkMode
from hydro_sdp.core.model.simulation import _ringing_increments
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / 'test'))
from support.stepped_ringing import (  # noqa: E402,I100,I202
    stepped_ringing_increments, strokes_into_stops)

RECORDS = 60


def main():
    """Time both forms over the same records and trial modes."""
    records = [strokes_into_stops(seed) for seed in range(RECORDS)]
    modes = [LinkMode.of(Oscillation(0.5 + 0.3 * k, 0.03 + 0.04 * k), 0.01) for k in range(10)]
    times, results = {}, {}
    # Warm: the first call imports scipy.signal.
    _ringing_increments(modes[0], *records[0][:2], 0.01, *records[0][2:3], *records[0][3])
    for name, form in (('sample by sample', stepped_ringing_increments),
                       ('stretches', _ringing_increments)):
        start = time.perf_counter()
        results[name] = [form(mode, increment, angles, 0.01, before, low, high)
                         for mode in modes for increment, angles, before, (low, high) in records]
        times[name] = (time.perf_counter() - start) / (len(modes) * RECORDS)
    gap = max(float(np.max(np.abs(a - b))) for a, b in zip(*results.values()))
    slow, fast = times['sample by sample'], times['stretches']
    print(f'per record: sample by sample {1e3 * slow:.2f} ms, stretches {1e3 * fast:.2f} ms, '
          f'ratio {slow / fast:.1f}x; largest difference {gap:.2g} deg')


if __name__ == '__main__':
    main()

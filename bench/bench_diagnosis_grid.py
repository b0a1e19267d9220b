"""
Benchmark the discrepancy workflow over a grid of joints from the independent generator.

Run with ``python bench/bench_diagnosis_grid.py [seeds] [seconds] [words...]``
(``words``: only those hidden words, e.g. ``oscillation none``; default all). Every word of the
vocabulary is hidden in turn (and nothing, ``none``) in joints simulated by
``test/support/joint_generator.py`` (its own maps, lags, integrator and effects: nothing
of the package's simulation), in volts and in percent, with random-level and
full-stroke programs, ``seeds`` draws each (default 2), records of ``seconds`` s
(default 60). Prints the confusion table (hidden word against the first word named),
the cases gone wrong and the shares right (targets: at least 95 % with the right word
first and the gap halved; ``none`` for every correct model).

"""

from pathlib import Path
import sys
import time

# The grid builds its cases with the test suite's helpers.
sys.path.insert(0, str(Path(__file__).resolve().parent.parent / 'test'))
from support.diagnosis_grid import (  # noqa: E402, I100
    make_case, PROGRAMS, run_case, UNITS, WORDS)
from support.grid_results import confusion_table, shares  # noqa: E402


def main():
    """Run the grid and print the table."""
    seeds = int(sys.argv[1]) if len(sys.argv) > 1 else 2
    seconds = float(sys.argv[2]) if len(sys.argv) > 2 else 60.0
    words = tuple(sys.argv[3:]) or WORDS
    unknown = [word for word in words if word not in WORDS]
    if unknown:
        sys.exit(f'error: unknown word {", ".join(unknown)} (known: {", ".join(WORDS)})')
    results = []
    started = time.perf_counter()
    for seed in range(seeds):
        for units in UNITS:
            for kind in PROGRAMS:
                for word in words:
                    if word == 'angle_limits' and kind == 'random':
                        continue  # Levels kept inside the stops never show them.
                    result = run_case(make_case(word, kind, units, seed, seconds=seconds))
                    results.append(result)
                    if not result.right:
                        print(f'  wrong: {word} ({kind}, {units}, seed {seed}) named '
                              f'{result.named}, MAE {result.mae_before:.3g} -> '
                              f'{result.mae_after:.3g} deg', flush=True)
    took = time.perf_counter() - started
    print('\n'.join(confusion_table(results, words)))
    print('\n'.join(shares(results)))
    print(f'{len(results)} cases in {took:.0f} s')


if __name__ == '__main__':
    main()

"""
Benchmark the discrepancy workflow over a grid of cases on the physics plant.

Run with ``python bench/bench_diagnosis_plant_grid.py [seeds] [programs] [words...]``
(``words``: only those hidden words, e.g. ``flow_sharing load_dependence``; default
all). Every word the
plant's physics can produce is hidden in turn (and nothing, ``none``) in models
identified from runs of the physics plant (``test/support/plant_grid.py`` says how
each model comes to lack its word, and which words the plant cannot produce and
why): the arm and the boom, in signed percent, a 0..100 % duty resting at 50 and
volts, ``programs`` (comma-separated, default ``random,stroke``: random levels and
full strokes), ``seeds`` draws each (default 1). Prints the
confusion table (hidden word against the first word named), the cases gone wrong,
the cases identify left nothing to remove from, and the shares right (the right word
first and the gap halved, the gap being the validation MAE above that of the model the
word was removed from, for ``flow_sharing`` above the model's own with the other joint
still; 30 % for ``load_dependence``; ``none`` for every model identified
on the same kind of runs), and the share with the gap taken as the whole MAE.

"""

from pathlib import Path
import sys
import time

# The grid builds its cases with the test suite's helpers.
sys.path.insert(0, str(Path(__file__).resolve().parent.parent / 'test'))
from support.grid_results import confusion_table, shares  # noqa: E402, I100
from support.plant_grid import LEFT_OUT, make_case, PROGRAMS, run_case, WORDS  # noqa: E402
from support.plant_programs import VARIANTS  # noqa: E402


def main():
    """Run the grid and print the table."""
    seeds = int(sys.argv[1]) if len(sys.argv) > 1 else 1
    programs = sys.argv[2].split(',') if len(sys.argv) > 2 else list(PROGRAMS)
    words = tuple(sys.argv[3:]) or WORDS
    unknown = [word for word in words if word not in WORDS]
    if unknown:
        sys.exit(f'error: unknown word {", ".join(unknown)} (known: {", ".join(WORDS)})')
    results, skipped = [], []
    started = time.perf_counter()
    for seed in range(seeds):
        for joint, units in VARIANTS:
            for kind in programs:
                for word in words:
                    case = make_case(word, kind, joint, units, seed)
                    if case is None:
                        skipped.append(f'{word} ({kind}, {joint} {units}, seed {seed})')
                        continue
                    result = run_case(case)
                    results.append(result)
                    verdict = 'right' if result.right else 'wrong'
                    print(f'  {verdict}: {word} ({kind}, {joint} {units}, seed {seed}) named '
                          f'{result.named}, MAE {result.mae_before:.3g} -> '
                          f'{result.mae_after:.3g} deg (floor {case.floor:.3g})', flush=True)
    took = time.perf_counter() - started
    print('\n'.join(confusion_table(results, words)))
    print('\n'.join(shares(results, 'gap above the floor halved (30 % for load_dependence)')))
    hidden = [r for r in results if r.word != 'none']
    print(f'with the gap the whole MAE: {sum(r.right_whole for r in hidden)}/{len(hidden)}')
    print(f'not hidden ({len(skipped)}: identify found nothing to remove, or the plant has '
          f'no such effect there): ' + '; '.join(skipped))
    print('left out: ' + '; '.join(f'{word}: {why}' for word, why in LEFT_OUT.items()))
    print(f'{len(results)} cases in {took:.0f} s')


if __name__ == '__main__':
    main()

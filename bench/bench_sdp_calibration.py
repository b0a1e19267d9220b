"""
Calibrate the SDP analysis's dependence test on joints with nothing left to find.

Run with ``python bench/bench_sdp_calibration.py [seeds] [seconds]``. Every case is a
true joint of the independent generator (``test/support/sdp_null_cases.py``: the
grid's random joints, nothing of the package's simulation) and two records of it:
``ratio`` cases give the analysis the true joint's own model (with its valve lag or its
direction-dependent delay when it has one), so no state dependence is left; ``arx``
cases give no model to a joint whose gain depends on the command alone, and every
state but the command is a null. Programs: random levels, full strokes pushed against
the stops, steps from rest and back; volts, percent resting at 50, signed percent;
noise 0.005-0.08 deg; a second joint on its own pump and a load the joint does not feel.

Prints the share of the null state/direction pairs significant at 5 % and at 1 %
(targets: at most about 5 % and 1 %), per target, errors (``white``: the sensor's
noise alone; ``drift``: a slow random factor of 5 % on the speed, correlated over
1-4 s, that the model does not have; ``lag``: the true joint's valve lag, which the
model's discrete lag follows to within a few hundredths of a degree at the first sample
after a change, so not a null at low noise) and program, and every pair at
``p <= 0.01``; ``seeds`` draws per target, program (and word) (default 2), records of
``seconds`` s (default 40).

"""

from pathlib import Path
import sys
import time

# The cases are built with the test suite's helpers.
sys.path.insert(0, str(Path(__file__).resolve().parent.parent / 'test'))
from hydro_sdp.core.identification.state_dependence import analyse  # noqa: E402, I100
from support.sdp_null_cases import null_case, null_pairs, PROGRAMS, RATIO_WORDS  # noqa: E402

#: Size of the slow random factor on the speed of the ``drift`` cases.
DRIFT = 0.05


def cases(seeds: int, seconds: float):
    """Yield the null cases of the table."""
    for seed in range(seeds):
        for program in PROGRAMS:
            for word in RATIO_WORDS:
                for drift in (0.0, DRIFT):
                    yield null_case('ratio', program, 3 * seed + RATIO_WORDS.index(word),
                                    word=word, drift=drift, seconds=seconds)
            for drift in (0.0, DRIFT):
                yield null_case('arx', program, seed, drift=drift, seconds=seconds)


def _line(target: str, kind: str, program: str, row: list[int]) -> str:
    count, pairs, five, one = row
    return (f'{target:8}{kind:8}{program:9}{count:6d}{pairs:7d}{five:6d} '
            f'({100 * five / pairs:4.1f} %){one:6d} ({100 * one / pairs:4.1f} %)')


def main():
    """Run the cases and print the table."""
    seeds = int(sys.argv[1]) if len(sys.argv) > 1 else 2
    seconds = float(sys.argv[2]) if len(sys.argv) > 2 else 40.0
    table: dict[tuple[str, str, str], list[int]] = {}
    by_state: dict[tuple[str, str], list[int]] = {}
    flagged = []
    firsts = []
    started = time.perf_counter()
    for case in cases(seeds, seconds):
        analysis = analyse(case.records, model=case.model)
        pairs = null_pairs(analysis, case.target)
        kind = 'lag' if case.word == 'valve_lag' else 'drift' if case.drift else 'white'
        row = table.setdefault((case.target, kind, case.program), [0, 0, 0, 0])
        row[0] += 1
        row[1] += len(pairs)
        row[2] += sum(p <= 0.05 for *_, p in pairs)
        row[3] += sum(p <= 0.01 for *_, p in pairs)
        flagged += [(case.name, pair) for pair in pairs if pair[3] <= 0.01]
        for _, state, _, p in pairs:
            count = by_state.setdefault((kind, state), [0, 0, 0])
            count[0] += 1
            count[1] += p <= 0.05
            count[2] += p <= 0.01
        if case.target == 'arx' and analysis.states[0].state != 'command':
            firsts.append((case.name, analysis.states[0].state))
        left = getattr(analysis, 'left_out', {})
        print(f'{case.name}: {len(pairs)} pairs, {sum(p <= 0.05 for *_, p in pairs)} at 5 %, '
              f'{sum(p <= 0.01 for *_, p in pairs)} at 1 %; left out {left}', flush=True)
    print(f'\n{"target":8}{"errors":8}{"program":9}{"cases":>6}{"pairs":>7}{"p<=0.05":>14}'
          f'{"p<=0.01":>14}')
    totals: dict[tuple[str, str], list[int]] = {}
    for (target, kind, program), row in sorted(table.items()):
        for key in ((target, kind), ('all', kind)):
            totals[key] = [a + b for a, b in zip(totals.get(key, [0, 0, 0, 0]), row)]
        print(_line(target, kind, program, row))
    for (target, kind), row in sorted(totals.items(), key=lambda item: item[0][0] == 'all'):
        print(_line(target, kind, 'all', row))
    print('per state (errors, state: pairs, at 5 %, at 1 %): ' + ', '.join(
        f'{kind} {state}: {n} {five} {one}' for (kind, state), (n, five, one)
        in sorted(by_state.items())))
    for name, (parameter, state, direction, p) in flagged:
        print(f'  p = {p:.3f}: {name}: {parameter} along {state} ({direction})')
    for name, state in firsts:
        print(f'  arx first state not the command: {name}: {state}')
    print(f'{time.perf_counter() - started:.0f} s')


if __name__ == '__main__':
    main()

"""
Benchmark ``oscillation`` on the same runs with the link's mode and without it.

Run with ``python bench/bench_oscillation.py [seeds] [programs] [sources]``
(``programs``: comma-separated, default ``random,stroke``, and ``short`` for the plant:
20 s random levels; ``sources``: ``generator``, ``plant`` or both, comma-separated, the
default). Each case is diagnosed twice on the same
commands, draws and noise: once with the link ringing on its oil column, once with it
settled. On the independent generator (``test/support/joint_generator.py``) the mode is
the grid's (1.5-4 Hz, damping 0.05-0.2) in volts, percent and signed percent; on the
physics plant it is the boom of ``config/physics_boom_compressible.yaml`` in signed
percent and volts, its compressibility section removed for the settled runs, the model
identified on settled runs. Prints what each was named, the MAE before and after, and
the counts (targets: ``oscillation`` with the gap halved on the ringing runs, ``none``
on the settled ones).

"""

from collections import Counter
from dataclasses import replace
from pathlib import Path
import sys
import time

# The cases are built with the test suite's helpers.
sys.path.insert(0, str(Path(__file__).resolve().parent.parent / 'test'))
from hydro_sdp.core.diagnosis.search import diagnose  # noqa: E402, I100
from hydro_sdp.core.model.joint_model import JointModel  # noqa: E402
import numpy as np  # noqa: E402
from support import diagnosis_grid, plant_grid  # noqa: E402
from support.plant_programs import levels, variant  # noqa: E402


def generator_pair(program, units, seed):
    """Return the nominal model and the ringing and settled (estimation, validation)."""
    word = 'oscillation'
    grid = diagnosis_grid
    made = {}
    for ringing in (True, False):
        rng = np.random.default_rng([seed, grid.WORDS.index(word), grid.PROGRAMS.index(program),
                                     list(grid.UNITS).index(units)])
        truth, nominal = grid.hide(word, rng, units)
        joint = replace(truth.joint, noise=0.02, mode=truth.joint.mode if ringing else None)
        records = grid.records_of(replace(truth, joint=joint), program, rng,
                                  name=f'{word} {program} {units} {seed}')
        made[ringing] = (records[:-1], records[-1:])
    return JointModel.from_mapping(nominal), made


def plant_pair(program, units, seed):
    """Return the model identified settled and the ringing and settled runs, and the floor."""
    seconds = 40.0
    rng = plant_grid._rng('boom', units, 'random' if program == 'short' else program, seed, 3)
    machine = variant('boom', units, rng, ringing=True)
    settled = replace(machine, joints=(replace(machine.joints[0], compressibility=None),))
    if program == 'short':
        # Short random levels (20 s: two to identify, two to estimate, one to validate),
        # which drift less than the grid's 40 s ones.
        def runs(m, first, count):
            return [levels(m, 20.0, 100 * seed + first + k) for k in range(count)]
        model = plant_grid._identify(settled, runs(settled, 0, 2), 'power_sat')
        made = {ringing: (runs(m, 10, 2), runs(m, 20, 1))
                for ringing, m in ((True, machine), (False, settled))}
        return model, made
    model = plant_grid._identify(
        settled, plant_grid._runs(settled, program, seed, 'identify', seconds=seconds),
        'power_sat')
    made = {ringing: tuple(plant_grid._runs(m, program, seed, part, seconds=seconds)
                           for part in ('estimate', 'validate'))
            for ringing, m in ((True, machine), (False, settled))}
    return model, made


def main():
    """Run both benches and print the counts."""
    seeds = int(sys.argv[1]) if len(sys.argv) > 1 else 2
    programs = sys.argv[2].split(',') if len(sys.argv) > 2 else ['random', 'stroke']
    counts = {key: Counter() for key in ('generator ringing', 'generator settled',
                                         'plant ringing', 'plant settled')}
    halved = Counter()
    started = time.perf_counter()
    sources = sys.argv[3].split(',') if len(sys.argv) > 3 else ['generator', 'plant']
    jobs = [('generator', units, generator_pair) for units in diagnosis_grid.UNITS]
    jobs += [('plant', units, plant_pair) for units in ('signed_percent', 'volt')]
    jobs = [job for job in jobs if job[0] in sources]
    for seed in range(seeds):
        for source, units, pair in jobs:
            for program in programs:
                if program == 'short' and source == 'generator':
                    continue
                model, made = pair(program, units, seed)
                for ringing in (True, False):
                    estimation, validation = made[ringing]
                    # Each with its grid's options (plant_grid.run_case, diagnosis_grid.run_case).
                    options = {} if source == 'generator' else {
                        'max_iterations': 1, 'max_delay': plant_grid.MAX_DELAY}
                    result = diagnose(estimation, model, validation=validation, **options)
                    key = f'{source} {"ringing" if ringing else "settled"}'
                    counts[key][result.effect] += 1
                    if ringing and result.effect == 'oscillation' and \
                            result.mae_after <= 0.5 * result.mae_before:
                        halved[source] += 1
                    print(f'  {key}: {program}, {units}, seed {seed}: {result.effect}, MAE '
                          f'{result.mae_before:.3g} -> {result.mae_after:.3g} deg', flush=True)
    for key, count in counts.items():
        print(f'{key}: ' + ', '.join(f'{word} {n}' for word, n in count.most_common()))
    for source in sources:
        print(f'{source} ringing: oscillation with the gap halved in {halved[source]}/'
              f'{sum(counts[f"{source} ringing"].values())}')
    print(f'took {time.perf_counter() - started:.0f} s')


if __name__ == '__main__':
    main()

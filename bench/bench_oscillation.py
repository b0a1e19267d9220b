"""
Benchmark ``oscillation`` on the same runs with the link's mode and without it.

Run with ``python bench/bench_oscillation.py [seeds] [programs] [sources] [spool_lag]``,
or ``python bench/bench_oscillation.py figure PATH`` for the figure of the preset boom
with its oil column and without, starts and stops without noise
(``docs/figures/oil_column.png``)
(``programs``: comma-separated, default ``random,stroke``, and ``short`` for the plant:
20 s random levels; ``sources``: ``generator``, ``plant`` or both, comma-separated, the
default; ``spool_lag``: the plant's valve with the preset's dead time and this spool lag, s,
instead of the grid's draws of both). Each case is diagnosed twice on the same
commands, draws and noise: once with the link ringing on its oil column, once with it
settled. On the independent generator (``test/support/joint_generator.py``) the mode is
the grid's (1.5-4 Hz, damping 0.05-0.2) in volts, percent and signed percent; on the
physics plant it is the boom of ``config/physics_boom_compressible.yaml`` in signed
percent and volts, its compressibility section removed for the settled runs, the model
identified on settled runs. Prints what each was named, the MAE before and after, the
gap above the floor (the same model's MAE on the settled runs), what the mode's
candidate found (frequency, damping, share of the held-out velocity residual and of the
windowed angle error it removes), and how far the ringing runs' angles are from the
settled ones, against what a dead time, a mode, a lost motion at reversals and a speed
factor per direction in series with the settled angles leave of it at best
(``_series_bound``).
Counts at the end (targets: ``oscillation`` with the gap above the floor halved on the
ringing runs, ``none`` on the settled ones).

"""

from collections import Counter
from dataclasses import replace
import math
from pathlib import Path
import sys
import time

# The cases are built with the test suite's helpers.
sys.path.insert(0, str(Path(__file__).resolve().parent.parent / 'test'))
from hydro_sdp.core.diagnosis.search import diagnose  # noqa: E402, I100
from hydro_sdp.core.model.bounded_sum import bounded_cumsum  # noqa: E402
from hydro_sdp.core.model.effects import Oscillation  # noqa: E402
from hydro_sdp.core.model.joint_model import JointModel  # noqa: E402
from hydro_sdp.core.model.link_mode import LinkMode  # noqa: E402
from hydro_sdp.io.documents import shipped_config  # noqa: E402
from hydro_sdp.io.plant_files import load_machine  # noqa: E402
import numpy as np  # noqa: E402
from scipy.optimize import minimize  # noqa: E402
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


def plant_pair(program, units, seed, spool_lag=None):
    """
    Return the model identified settled and the ringing and settled runs.

    ``spool_lag``: the valve's spool lag, s, with the preset's dead time, instead of the
    grid's draws of both.
    """
    seconds = 40.0
    rng = plant_grid._rng('boom', units, 'random' if program == 'short' else program, seed, 3)
    machine = variant('boom', units, rng, ringing=True)
    if spool_lag is not None:
        preset = load_machine(shipped_config('physics_boom_compressible.yaml')).joints[0]
        valve = replace(machine.joints[0].valve, dead_time=preset.valve.dead_time,
                        time_constant=spool_lag)
        machine = replace(machine, joints=(replace(machine.joints[0], valve=valve),))
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


def _mode_found(result):
    """Return what the mode's candidate of the first round found, in words."""
    mode = next(c for c in result.rounds[0] if c.effect == 'oscillation')
    if 'frequency' not in mode.parameters:
        return f'mode refused: {mode.evidence}'
    return (f'mode {mode.parameters["frequency"]:.3g} Hz, damping '
            f'{mode.parameters["damping"]:.2g}, {"accepted" if mode.accepted else "refused"}, '
            f'removes {100 * mode.gain:.0f} % of the velocity residual and '
            f'{100 * mode.held_out:.0f} % of the windowed error')


def _series_bound(made):
    """
    Return how far the ringing runs' angles are from the settled ones, and what forms take.

    The settled runs' own angles (same commands, draws and noise) are put through a dead
    time, a lost motion at reversals (a play on the actuator: the oil decompressed and
    compressed again before the link turns), a mode and a speed factor per direction (the
    oil compressed or released as the load pressure changes along the stroke) in series,
    each fitted to the ringing runs' angles (mean absolute error, while the commands agree,
    ``_AWAY`` deg or more from the run's extremes: at a stop a model's mode and a joint's
    link part ways).
    What the best fit leaves, those forms added to a model as good as the settled joint
    itself would not remove.
    """
    pairs = []
    whole = 0
    for part in (0, 1):
        for ringing, settled in zip(made[True][part], made[False][part]):
            # Strokes end at the stop and random levels turn back before it, the ringing
            # link a few samples apart: compared while the commands agree.
            n = min(ringing.y.size, settled.y.size)
            whole += n
            n = int(np.argmax(np.r_[ringing.v[:n] != settled.v[:n], True]))
            angles = settled.y[:n]
            away = (angles > angles.min() + _AWAY) & (angles < angles.max() - _AWAY)
            pairs.append((angles, ringing.y[:n], away, float(np.median(np.diff(settled.t)))))

    def left(x, shift, ring, play, scaled=False):
        total = count = 0.0
        frequency, damping = math.exp(x[0]), min(max(float(x[1]), 0.01), 0.95)
        half = 0.5 * max(float(x[2]), 0.0) if play else 0.0
        for angles, target, away, dt in pairs:
            if ring and frequency >= 0.5 / dt:
                return math.inf
            moved = np.r_[np.full(shift, angles[0]), angles[:angles.size - shift]]
            if scaled:
                # Each direction's speed scaled by its own factor (x[3], x[4]: percent).
                steps = np.diff(moved)
                steps = steps * (1.0 + 0.01 * np.where(steps > 0.0, x[3], x[4]))
                moved = np.r_[moved[0], moved[0] + np.cumsum(steps)]
            if half:
                moved = moved + bounded_cumsum(0.0, -np.diff(moved), -half, half)
            if ring:
                mode = LinkMode.of(Oscillation(frequency, damping), dt)
                before = float(angles[10] - angles[0]) / (10.0 * dt)
                # Moving at the start, the link trails its actuator by the mode's lead.
                moved = mode.ring(moved + mode.lead * before, dt, before)
            total += float(np.abs(moved - target)[away].sum())
            count += int(away.sum())
        return total / count

    compared = sum(int(away.sum()) for _, _, away, _ in pairs)
    raw = left(np.zeros(5), 0, False, False)
    words = [f'over {100 * compared / whole:.0f} % of the samples the runs part by {raw:.3f} '
             'deg; in series with the settled angles']
    for ring, play, scaled, label in (
            (False, False, False, 'a dead time leaves'), (True, False, False, 'with a mode'),
            (False, True, False, 'with a play'), (True, True, False, 'with both'),
            (False, True, True, 'with the play and a speed factor per direction')):
        # The fit moves the mode's frequency and damping with a ring, the play with a play,
        # the two factors with the speeds scaled.
        free = ([0, 1] if ring else []) + ([2] if play else []) + ([3, 4] if scaled else [])
        best = (math.inf, np.zeros(5), 0)
        for shift in range(_LONGEST_SHIFT + 1):
            for frequency in (1.0, 2.0, 4.0) if ring else (1.0,):
                x = np.array([math.log(frequency), 0.15, 0.4 * play, 0.0, 0.0])

                def cost(values, x=x, shift=shift, ring=ring, play=play, scaled=scaled):
                    x[free] = values
                    return left(x, shift, ring, play, scaled)
                if free:
                    fitted = minimize(cost, x[free], method='Nelder-Mead')
                    x[free] = fitted.x
                reached = cost(x[free])
                if reached < best[0]:
                    best = (reached, x.copy(), shift)
        cost, x, shift = best
        found = [f'{shift} samples later']
        if ring:
            found.append(f'{math.exp(x[0]):.3g} Hz, damping '
                         f'{min(max(float(x[1]), 0.01), 0.95):.2g}')
        if play:
            found.append(f'play {max(x[2], 0.0):.3g} deg')
        if scaled:
            found.append(f'speeds {x[3]:+.2g} % and {x[4]:+.2g} % (positive, negative)')
        words.append(f'{label} {cost:.3f} ({100 * (1.0 - cost / raw):.0f} % less; '
                     + ', '.join(found) + ')')
    return ', '.join(words[:2]) + '; ' + '; '.join(words[2:])


#: How far from a run's extremes the bound compares its angles, deg.
_AWAY = 2.0
#: Longest extra dead time the bound tries, samples.
_LONGEST_SHIFT = 8


def figure(path):
    """Draw the preset boom's speed and angle with its oil column and settled, and save it."""
    from hydro_sdp.core.synthetic.physics.machine import simulate_plant
    from hydro_sdp.plots.figures import MEASURED, MODEL, new_figure, save_figure
    machine = load_machine(shipped_config('physics_boom_compressible.yaml'))
    joint = replace(machine.joints[0], noise=0.0)
    ringing = replace(machine, joints=(joint,))
    settled = replace(machine, joints=(replace(joint, compressibility=None),))
    dt = 0.005
    plot, axes = new_figure(2, height=2.4, width=10.0)
    commands = np.r_[np.zeros(200), np.full(600, 60.0), np.zeros(600), np.full(500, -100.0),
                     np.zeros(500)][:, None]
    angles = {ring: simulate_plant(m, commands, dt).angles[:, 0]
              for ring, m in ((True, ringing), (False, settled))}
    t = np.arange(commands.shape[0]) * dt
    for ring, colour, label in ((False, MODEL, 'settled (no oil column)'),
                                (True, MEASURED, 'on its oil column (2 Hz)')):
        axes[0].plot(t, np.gradient(angles[ring], dt), color=colour, label=label)
    axes[0].set_ylabel('speed, deg/s')
    axes[0].legend(loc='lower left')
    axes[0].set_title('The boom of physics_boom_compressible.yaml: 60 % from rest, held '
                      'still, then -100 % into its lower stop')
    axes[1].plot(t, angles[True] - angles[False], color=MEASURED)
    axes[1].set_ylabel('angle apart, deg')
    axes[1].set_xlabel('time, s')
    print(f'wrote {save_figure(plot, path)}')


def main():
    """Run both benches and print the counts."""
    if len(sys.argv) > 1 and sys.argv[1] == 'figure':
        figure(sys.argv[2] if len(sys.argv) > 2 else 'oil_column.png')
        return
    seeds = int(sys.argv[1]) if len(sys.argv) > 1 else 2
    programs = sys.argv[2].split(',') if len(sys.argv) > 2 else ['random', 'stroke']
    counts = {key: Counter() for key in ('generator ringing', 'generator settled',
                                         'plant ringing', 'plant settled')}
    halved = Counter()
    started = time.perf_counter()
    sources = sys.argv[3].split(',') if len(sys.argv) > 3 else ['generator', 'plant']
    spool_lag = float(sys.argv[4]) if len(sys.argv) > 4 else None
    jobs = [('generator', units, generator_pair) for units in diagnosis_grid.UNITS]
    jobs += [('plant', units, plant_pair) for units in ('signed_percent', 'volt')]
    jobs = [job for job in jobs if job[0] in sources]
    for seed in range(seeds):
        for source, units, pair in jobs:
            for program in programs:
                if program == 'short' and source == 'generator':
                    continue
                model, made = (pair(program, units, seed) if source == 'generator' else
                               pair(program, units, seed, spool_lag))
                results = {}
                for ringing in (False, True):
                    estimation, validation = made[ringing]
                    # Each with its grid's options (plant_grid.run_case, diagnosis_grid.run_case).
                    options = {} if source == 'generator' else {
                        'max_iterations': 1, 'max_delay': plant_grid.MAX_DELAY}
                    results[ringing] = diagnose(estimation, model, validation=validation,
                                                **options)
                floor = results[False].mae_before
                for ringing in (True, False):
                    result = results[ringing]
                    key = f'{source} {"ringing" if ringing else "settled"}'
                    counts[key][result.effect] += 1
                    line = (f'  {key}: {program}, {units}, seed {seed}: {result.effect}, MAE '
                            f'{result.mae_before:.3g} -> {result.mae_after:.3g} deg')
                    if ringing:
                        if result.effect == 'oscillation' and result.mae_after - floor <= \
                                0.5 * (result.mae_before - floor):
                            halved[source] += 1
                        line += (f' (floor {floor:.3g}); {_mode_found(result)}; '
                                 + _series_bound(made))
                    print(line, flush=True)
    for key, count in counts.items():
        print(f'{key}: ' + ', '.join(f'{word} {n}' for word, n in count.most_common()))
    for source in sources:
        print(f'{source} ringing: oscillation with the gap above the floor halved in '
              f'{halved[source]}/'
              f'{sum(counts[f"{source} ringing"].values())}')
    print(f'took {time.perf_counter() - started:.0f} s')


if __name__ == '__main__':
    main()

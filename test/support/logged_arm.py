"""
An excavator arm logged as a machine's user logs it: one duty per run, 40-100 % only.

The joint is :mod:`support.joint_generator`'s (nothing from the package's simulation): a
measured-looking convex valve curve in signed percent duty with a dead-zone of about
36 %, a 0.25 s dead time and a 0.12 s spool lag, stops at -45 and 40 deg, and a valve
without pressure compensation, so that a heavier load slows the arm lifting and speeds
it lowering. Each run holds one duty from stop to stop and back; no run goes below
40 %, where the arm barely moves. Run as a script, it identifies the arm as the issue's
user did and prints what identify reports and the errors over runs it did not see::

    .venv/bin/python test/support/logged_arm.py

"""

from __future__ import annotations

import math
from pathlib import Path
import sys

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from support.joint_generator import Joint, Machine, record, SpeedMap  # noqa: E402

DT = 0.01
DUTIES = (40, 50, 60, 70, 80, 90, 100)
ESTIMATION = (40, 60, 80, 100)
VALIDATION = (50, 70, 90)
#: The true dead-zone, percent duty.
DEAD_ZONE = (-37.0, 36.0)
STOPS = (-45.0, 40.0)
#: Supply pressure and the two loads, bar.
SUPPLY = 200.0
LOADS = {'low': 40.0, 'high': 110.0}
CURVE = ((-100.0, -26.5), (-90.0, -25.6), (-80.0, -23.0), (-70.0, -17.5), (-60.0, -10.0),
         (-50.0, -3.9), (-40.0, -0.9), (DEAD_ZONE[0], 0.0), (DEAD_ZONE[1], 0.0),
         (40.0, 0.7), (45.0, 2.0), (50.0, 4.4), (60.0, 11.0), (70.0, 19.0), (80.0, 25.0),
         (90.0, 28.0), (100.0, 29.2))


def load_factor(load: float, direction: float) -> float:
    """Speed of an uncompensated valve at ``load`` (bar), relative to the low load."""
    reference = LOADS['low']
    if direction > 0.0:
        return math.sqrt((SUPPLY - load) / (SUPPLY - reference))
    return math.sqrt((SUPPLY + load) / (SUPPLY + reference))


ARM = Joint(SpeedMap('table', DEAD_ZONE, points=CURVE), delay=0.25, spool_lag=0.12,
            stops=STOPS, load_factor=load_factor, noise=0.01)


def stroke_commands(duty: float, load: float) -> np.ndarray:
    """Rest, one duty up to the upper stop and on for a second, rest, back down, rest."""
    low, high = STOPS
    pieces = [np.zeros(100)]
    for sign in (1.0, -1.0):
        speed = abs(ARM.speed_map.speed(sign * duty)) * load_factor(load, sign)
        seconds = (high - low) / max(speed, 0.05) + ARM.delay + 5 * ARM.spool_lag + 1.5
        pieces += [np.full(int(seconds / DT), sign * duty), np.zeros(100)]
    return np.concatenate(pieces)


def runs(load: str = 'low', duties=DUTIES, seed: int = 0) -> dict[int, object]:
    """Return one record per duty at a load, keyed by duty, as a logger writes them."""
    out = {}
    pressure = LOADS[load]
    for index, duty in enumerate(duties):
        commands = stroke_commands(duty, pressure)
        out[duty] = record(Machine((ARM,), DT, ('arm',)), commands[:, None],
                           angles0=[STOPS[0]], load=np.full(commands.size, pressure),
                           seed=seed + index, source=f'arm {load} {duty} %')
    return out


def main() -> None:
    """Identify on 40/60/80/100 % and report, with the errors on 50/70/90 %."""
    from hydro_sdp.core.identification.evaluation import evaluate, mean_errors
    from hydro_sdp.core.identification.identify import identify

    for train, test in (('low', 'low'), ('high', 'low')):
        fit = runs(train, ESTIMATION, seed=1)
        held = runs(test, VALIDATION if train == test else DUTIES, seed=20)
        result = identify(list(fit.values()))
        model = result.model
        print(f'identified at the {train} load, held out: {test} load')
        print(f'  family {model.kind}: {result.family.verdict() if result.family else "-"}')
        print(f'  dead zone {model.dead_zone} (true {DEAD_ZONE})')
        for entry in model.undetermined:
            print(f'  {entry.describe()}')
        for check in result.effect_checks:
            print(f'  {check.describe()}')
        scores = evaluate(list(held.values()), model)
        print('  held-out MAE per run', [round(s.model, 2) for s in scores],
              'mean', round(mean_errors(scores)['per_record']['model'], 3))


if __name__ == '__main__':
    main()

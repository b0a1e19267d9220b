"""
Confusions of the diagnosis on the independent generator: the rare stop, play against lag.

* **Rare stop**: :func:`support.failure_cases.rare_stop`'s joint (stops at -40 and 55 deg),
  its model identified from steps that never reach a stop, diagnosed on a one-minute run
  of random levels that meets the top stop for about 2 s, judged on another; seeds
  change both runs.
* **Play against lag**: the same map and delay with play between actuator and sensor
  (``backlash``, lost motion after reversals only) or with a first-order lag of the
  speed (``valve_lag``, a tail after every change); the model identified from steps of
  the joint without either, diagnosed on 40 s of random levels and judged on another.

Prints one row per case and seed (the word named, the validation MAE before and after)
and the tally of each hidden word against the named one::

    .venv/bin/python test/support/confusions.py [seeds] [case ...]

(cases: ``rare``, ``rare_slow``, ``play``, ``lag``, ``small_play``, ``small_lag``)

"""

from __future__ import annotations

from collections import Counter
from dataclasses import replace
from pathlib import Path
import sys

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from support.failure_cases import (  # noqa: E402
    _random_level, _rare_program, DT, STOPPED)
from support.joint_generator import Machine, record  # noqa: E402

#: The hidden effects of the play-against-lag table: large, and small beside the noise
#: (0.02 deg) and the delay (0.12 s).
PLAY = {'play': 1.0, 'small_play': 0.3}
LAG = {'lag': 0.2, 'small_lag': 0.06}
FREE = replace(STOPPED, stops=(-80.0, 80.0))


def _steps(joint):
    parts = [np.zeros(100)]
    for size in [1.0, 1.3, 1.6, 2.0, 2.5, 3.0, 4.0, 5.0, 6.5, 8.0]:
        up, down = joint.speed_map.speed(size), -joint.speed_map.speed(-size)
        hold = 150
        parts += [np.full(hold, size), np.zeros(60),
                  np.full(int(round(hold * up / down)), -size), np.zeros(60)]
    return np.concatenate(parts)


def _levels(joint, seed: int, seconds: float) -> np.ndarray:
    rng = np.random.default_rng(seed)
    n = int(round(seconds / DT))
    v = np.zeros(n)
    k, y = 100, 0.0
    while k < n:
        level, m, y = _random_level(joint, rng, y, (1.5, 7.0), margin=30.0)
        v[k:k + m] = level
        k += m
    return v


def case(word: str, seed: int):
    """Return the model, the estimation and the validation records of one hidden word."""
    from hydro_sdp.core.identification.identify import identify
    if word.startswith('rare'):
        # rare_slow: the real-arm-like timing, a 0.25 s dead time and a 0.15 s spool lag.
        base = STOPPED if word == 'rare' else replace(STOPPED, delay=0.25, spool_lag=0.15)
        hidden = base
        program = _rare_program
        seconds = 60.0
    else:
        base = FREE
        hidden = replace(FREE, play=PLAY[word]) if word in PLAY else \
            replace(FREE, lag=LAG[word])
        program = _levels
        seconds = 40.0
    steps = record(Machine((base,)), _steps(base)[:, None], angles0=[0.0], seed=1,
                   source='steps')
    model = identify([steps], kind='sdp').model
    runs = [record(Machine((hidden,)), program(hidden, s, seconds)[:, None], angles0=[0.0],
                   seed=s, source=f'levels {s}') for s in (11 + 2 * seed, 12 + 2 * seed)]
    return model, runs[:1], runs[1:]


HIDDEN = {'rare': 'angle_limits', 'rare_slow': 'angle_limits', 'play': 'backlash',
          'lag': 'valve_lag', 'small_play': 'backlash', 'small_lag': 'valve_lag'}


def main(seeds: int, words: list[str]) -> None:
    """Print the word named per hidden word and seed, and the tally."""
    from hydro_sdp.core.diagnosis import diagnose
    for word in words:
        tally: Counter[str] = Counter()
        halved = 0
        for seed in range(seeds):
            model, estimation, validation = case(word, seed)
            result = diagnose(estimation, model, validation=validation, max_iterations=1)
            first = result.ledger[0] if result.ledger else None
            ratio = first.mae_after / first.mae_before if first else 1.0
            halved += result.effect == HIDDEN[word] and ratio <= 0.5
            tally[result.effect] += 1
            print(f'{HIDDEN[word]} seed {seed}: named {result.effect}, MAE '
                  f'{result.mae_before:.3g} -> {result.mae_after:.3g} deg '
                  f'(x{ratio:.2f}); candidates '
                  + ', '.join(f'{c.effect} {100 * c.held_out:.0f}%{"*" if c.accepted else ""}'
                              for c in result.candidates[:4]), flush=True)
        print(f'{HIDDEN[word]}: ' + ', '.join(f'{k} {n}' for k, n in tally.most_common())
              + f' of {seeds}; right with the gap halved {halved}', flush=True)


if __name__ == '__main__':
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 5, sys.argv[2:] or list(HIDDEN))

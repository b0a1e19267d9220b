"""
The rest command of a joint's records: the command at which the joint stands still.

The reasoning is in docs/methods.md section 13.1.

"""

from __future__ import annotations

from typing import Sequence

from hydro_sdp.core.arrays import FloatArray
import numpy as np

#: A held command counts as "still" when the joint's median step there is at most this
#: many times the stillest held command's (and the noise floor).
STILL_FACTOR = 3.0


def command_motion(pairs: Sequence[tuple[FloatArray, FloatArray]]
                   ) -> dict[float, tuple[int, float]]:
    """
    Count the samples and the median angle step of each held command, per record.

    ``pairs``: commands and angles (degrees) of each record.
    Returns: command -> (samples in the second half of the stretches it was held, median
    ``|y_k - y_{k-1}|`` over them, degrees).
    """
    values: list[FloatArray] = []
    steps: list[FloatArray] = []
    for v, y in pairs:
        v = np.asarray(v, dtype=np.float64)
        y = np.asarray(y, dtype=np.float64)
        if v.size < 2:
            continue
        # The second half of every stretch of one held command: the joint has settled
        # there from the previous command (delay, valve lag) whatever its dynamics.
        starts = np.r_[0, np.flatnonzero(np.diff(v)) + 1]
        lengths = np.diff(np.r_[starts, v.size])
        position = np.arange(v.size) - np.repeat(starts, lengths)
        settled = (2 * position >= np.repeat(lengths, lengths)) & (position >= 1)
        values.append(v[1:][settled[1:]])
        steps.append(np.abs(np.diff(y))[settled[1:]])
    if not values:
        return {}
    v_all, step_all = np.concatenate(values), np.concatenate(steps)
    order = np.lexsort((step_all, v_all))
    v_all, step_all = v_all[order], step_all[order]
    unique, first, counts = np.unique(v_all, return_index=True, return_counts=True)
    return {float(u): (int(c), float(np.median(step_all[f:f + c])))
            for u, f, c in zip(unique, first, counts)}


def estimate_rest_command(pairs: Sequence[tuple[FloatArray, FloatArray]], *,
                          neutral: float | None = None,
                          input_limits: tuple[float, float] | None = None,
                          min_share: float = 0.01) -> float:
    """
    Choose the rest command of one joint's records.

    ``pairs``: commands and angles (degrees) of each record.
    ``neutral``: the valve's neutral command, if known: it is the answer.
    ``input_limits``: the valve's command range: its middle is the preferred rest when the range
    does not contain 0 (a 0..100 % duty resting at 50).
    ``min_share``: share of the samples a command must be held for to be a candidate.
    """
    if neutral is not None:
        return float(neutral)
    motion = command_motion(pairs)
    total = sum(count for count, _ in motion.values())
    candidates = {value: step for value, (count, step) in motion.items()
                  if count >= max(min_share * total, 2)}
    if not candidates:
        return 0.0
    floor = min(candidates.values())
    still = {value: step for value, step in candidates.items()
             if step <= STILL_FACTOR * floor + 1e-12}
    low = min(float(np.min(v)) for v, _ in pairs if len(v))
    high = max(float(np.max(v)) for v, _ in pairs if len(v))
    preferred: list[float] = []
    if input_limits is not None:
        preferred.append(0.0 if input_limits[0] <= 0.0 <= input_limits[1]
                         else 0.5 * (input_limits[0] + input_limits[1]))
    if low <= 0.0 <= high:
        preferred.append(0.0)
    preferred.append(0.5 * (low + high))
    for value in preferred:
        if value in still:
            return value
    # The still command held longest; among equals the one nearest the middle of the range.
    middle = 0.5 * (low + high)
    return max(still, key=lambda value: (motion[value][0], -abs(value - middle), -value))

"""Whether a candidate's reduction of the residual is real: a block bootstrap (methods 8.4)."""

from __future__ import annotations

from dataclasses import dataclass
import math
from typing import Sequence

from hydro_sdp.core.arrays import FloatArray
from hydro_sdp.core.identification.state_dependence.significance import block_length
import numpy as np

#: Bootstrap replicates of the test.
REPLICATES = 999
#: Significance level.
ALPHA = 0.01


@dataclass(frozen=True)
class Reduction:
    """
    A candidate's reduction of the squared velocity residual and its test.

    Parameters
    ----------
    gain : float
        Share of the model's squared residual the candidate removes (negative: it adds).
    z : float
        Standard score of the reduction under the bootstrap's null.
    p_value : float
        Share of bootstrap replicates (with the data) whose reduction reaches it.
    block : int
        Block length, samples.

    """

    gain: float
    z: float
    p_value: float
    block: int

    @property
    def significant(self) -> bool:
        """Whether the reduction is significant: ``p_value <= ALPHA`` and it removes some."""
        return self.p_value <= ALPHA and self.gain > 0.0


def bootstrap_block(candidate: Sequence[FloatArray], shortest: int) -> int:
    """
    Return the block length: twice the candidate residual's correlation, at least ``shortest``.

    ``candidate``: the candidate's velocity residuals, run by run.
    ``shortest``: fewest samples per block.
    Returns: samples per block.
    """
    longest = max((series.size for series in candidate), default=0)
    if longest == 0:
        return max(1, shortest)
    series = max(candidate, key=lambda values: values.size)
    return max(shortest, block_length(series))


def reduction_test(base: Sequence[FloatArray], candidate: Sequence[FloatArray], block: int, *,
                   replicates: int = REPLICATES, seed: int = 0) -> Reduction:
    """
    Test the candidate's reduction of the squared residual by a block bootstrap.

    ``base``, ``candidate``: velocity residuals of the model and of the candidate, run by run (same
    shapes).
    ``block``: samples per block (the last block of a run may be shorter).
    Returns: share removed, standard score, p-value and block length.
    """
    sums: list[float] = []
    total = removed = changed = 0.0
    for before, after in zip(base, candidate):
        if before.size == 0:
            continue
        change = before - after
        total += float(np.dot(before, before))
        removed += float(np.dot(before, before) - np.dot(after, after))
        changed += float(np.dot(change, change))
        products = after * change
        edges = np.arange(0, products.size, block)
        sums.extend(np.add.reduceat(products, edges).tolist())
    if not total > 0.0 or not sums:
        return Reduction(0.0, 0.0, 1.0, block)
    c = np.asarray(sums)
    spread = float(math.sqrt(np.dot(c, c)))
    gain = removed / total
    if spread == 0.0:
        # The candidate leaves nothing where it changes anything: no noise to weigh it by.
        real = removed > 0.0
        return Reduction(gain, math.inf if real else 0.0, 1.0 / (1 + replicates) if real
                         else 1.0, block)
    z = (removed + changed) / (2.0 * spread)
    rng = np.random.default_rng(seed)
    signs = rng.choice(np.array([-1.0, 1.0]), size=(replicates, c.size))
    null = 2.0 * (signs @ c) - changed
    exceed = int(np.count_nonzero(null >= removed))
    return Reduction(gain, z, (1.0 + exceed) / (1.0 + replicates), block)

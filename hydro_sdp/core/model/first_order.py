"""The first-order recursion ``y_k = a y_{k-1} + b x_k``, in numpy (methods 2.3)."""

from __future__ import annotations

import math

from hydro_sdp.core.arrays import FloatArray
import numpy as np

#: Largest exponent ``k |ln a|`` within a block: ``a^-k`` stays below e^600.
_EXPONENT = 600.0
#: Ranks ``1, 2, ...`` the powers of a pole are taken at, grown as longer series come.
_ranks = np.arange(1.0, 4097.0)


def _powers(a: float, count: int) -> FloatArray:
    """Return ``a^1 .. a^count``."""
    global _ranks
    if count > _ranks.size:
        _ranks = np.arange(1.0, 2.0 * count + 1.0)
    return np.power(a, _ranks[:count])


def _block(x: FloatArray, a: float, b: float, before: float | FloatArray) -> FloatArray:
    """Run the recursion over one block, from ``y_{-1} = before``."""
    powers = _powers(a, x.shape[-1])
    out = np.divide(x, powers)
    np.cumsum(out, axis=-1, out=out)
    if b != 1.0:
        out *= b
    if np.ndim(before):
        out += np.asarray(before)[..., None]
    elif before:
        out += before
    out *= powers
    return out


def first_order(x: FloatArray, a: float, b: float = 1.0,
                before: float | FloatArray = 0.0) -> FloatArray:
    """
    Run ``y_k = a y_{k-1} + b x_k`` along the last axis of ``x``.

    ``x``: input, one series per row of the last axis.
    ``a``: the pole, ``-1 <= a <= 1`` (a valve lag: ``exp(-dt / T)``).
    ``b``: the input gain (a lag of unit steady gain: ``1 - a``).
    ``before``: ``y_{-1}``, the output before the first sample (one per series, or one for all).
    """
    if not -1.0 <= a <= 1.0:
        raise ValueError(f'the pole of a first-order recursion must lie in [-1, 1], got {a}')
    x = np.asarray(x, dtype=np.float64)
    if a == 0.0:
        return b * x
    size = x.shape[-1]
    block = size if abs(a) == 1.0 else max(1, int(_EXPONENT / -math.log(abs(a))))
    if size <= block:
        return _block(x, a, b, before)
    # All blocks at once: each block's sum from zero, then the state carried across
    # blocks (the same operations, in the same order, as block after block). The whole
    # blocks are a view of the output and the last, shorter one follows: no padding.
    count = -(-size // block)
    whole = (count - 1 if size % block else count) * block
    out = np.empty(x.shape)
    blocks = out[..., :whole].reshape(x.shape[:-1] + (whole // block, block))
    tail = out[..., whole:]
    powers = _powers(a, block)
    np.divide(x[..., :whole].reshape(blocks.shape), powers, out=blocks)
    np.cumsum(blocks, axis=-1, out=blocks)
    np.divide(x[..., whole:], powers[:size - whole], out=tail)
    np.cumsum(tail, axis=-1, out=tail)
    if b != 1.0:
        out *= b
    last = float(powers[-1])
    # The state entering each block follows from the ends of the blocks before it.
    ends = blocks[..., :count - 1, -1]
    starts = _carried(ends, last, before)
    if starts is None and x.ndim == 1:
        # One series: carry the state in Python floats (the same IEEE arithmetic, without
        # an array operation per block).
        state = float(np.asarray(before, dtype=np.float64))
        states = [state]
        for end in ends.tolist():
            state = (end + state) * last
            states.append(state)
        starts = np.array(states)
    elif starts is None:
        starts = np.empty(x.shape[:-1] + (count,))
        carried = np.broadcast_to(np.asarray(before, dtype=np.float64), x.shape[:-1])
        starts[..., 0] = carried
        for index in range(count - 1):
            carried = (ends[..., index] + carried) * last
            starts[..., index + 1] = carried
    blocks += starts[..., :whole // block, None]
    blocks *= powers
    tail += starts[..., -1:]
    tail *= powers[:size - whole]
    return out


def _carried(ends: FloatArray, last: float, before: float | FloatArray) -> FloatArray | None:
    """Return the state entering each block, all blocks at once, or None where it cannot."""
    first = np.broadcast_to(np.asarray(before, dtype=np.float64), ends.shape[:-1])
    starts = np.empty(ends.shape[:-1] + (ends.shape[-1] + 1,))
    starts[..., 0] = first
    if ends.shape[-1] > 0:
        starts[..., 1] = (ends[..., 0] + first) * last
        np.multiply(ends[..., 1:], last, out=starts[..., 2:])
        middle = ends[..., 1:]
        if not np.array_equal(middle + starts[..., 1:-1], middle):
            return None
    return starts

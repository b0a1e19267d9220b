"""Experiments arranged for fast residual evaluation, and what a fit returns (methods 2.3)."""

from __future__ import annotations

from dataclasses import dataclass, field
import math
from typing import Callable, Generic, get_args, Literal, Sequence, TypeVar

from hydro_sdp.core.arrays import FloatArray, IntArray
from hydro_sdp.core.errors import DataError
from hydro_sdp.core.identification.experiment import Experiment
from hydro_sdp.core.model.first_order import first_order
from hydro_sdp.core.model.static_maps import StaticMap
from hydro_sdp.core.model.timing import delayed_at, SamplePeriod
import numpy as np
import numpy.typing as npt

RateFunction = Callable[[FloatArray], FloatArray]
#: How a map is fitted to the raw angles: regret-regression or output error.
FitMethod = Literal['rr', 'oe']
FIT_METHODS: tuple[FitMethod, ...] = get_args(FitMethod)

#: Trust-region solver of the bounded fits on the raw angles: LSMR works on the tall
#: Jacobian (one row per sample) directly, where the exact solver takes its SVD at
#: every step, the cost of a fit on a long record.
TR_SOLVER: Literal['lsmr'] = 'lsmr'

MapT = TypeVar('MapT', bound=StaticMap, covariant=True)


#: Padded cells a bucket may gain by joining the next longer one: fewer than the numpy
#: calls of a bucket of its own cost per evaluation.
MERGE_CELLS = 2048


def buckets_of(lengths: IntArray) -> list[IntArray]:
    """
    Group experiments by length into the rows of padded 2-D blocks.

    ``lengths``: predicted samples of each experiment.
    """
    sizes = 2 ** np.ceil(np.log2(np.maximum(lengths, 1))).astype(int)
    out: list[IntArray] = []
    for size in np.unique(sizes):
        members = np.flatnonzero(sizes == size)
        if out and out[-1].size * (int(lengths[members].max()) - int(lengths[out[-1]].max())) \
                <= MERGE_CELLS:
            out[-1] = np.concatenate([out[-1], members])
        else:
            out.append(members)
    return out


class FitData:
    """
    Experiments arranged for fast residual evaluation.

    ``dt``: sample period, s.
    ``lag``: valve lag time constant, s (0: none); each experiment's lag starts in steady state at
    its first delayed command.
    ``gains``: per experiment, a factor on the speed of each predicted sample (the stroke geometry
    at the measured angle before it); default: 1.
    """

    def __init__(self, experiments: Sequence[Experiment], delay: int, dt: SamplePeriod,
                 lag: float = 0.0, gains: Sequence[FloatArray] | None = None) -> None:
        if not experiments:
            raise DataError('no experiments to fit')
        self.experiments = tuple(experiments)
        self.delay = delay
        self.dt = dt
        self.lag = lag
        self.pole = math.exp(-dt / lag) if lag > 0.0 else 0.0
        delayed_all, observed_all, initial_all = [], [], []
        for experiment in experiments:
            k = np.arange(experiment.start + 1, experiment.y.size)
            delayed_all.append(delayed_at(experiment.v, k, delay))
            observed_all.append(experiment.y[k])
            initial_all.append(float(experiment.y[experiment.start]))
        self.levels, inverse = np.unique(np.concatenate(delayed_all), return_inverse=True)
        self.samples = int(inverse.size)
        lengths = np.array([d.size for d in delayed_all])
        offsets = np.r_[0, np.cumsum(lengths)]
        self.buckets: list[tuple[IntArray, IntArray, FloatArray, npt.NDArray[np.bool_],
                                 FloatArray]] = []
        self.gains: list[FloatArray] = []
        self._padded: list[IntArray] = []
        self._samples: list[IntArray | None] = []
        self._padding: list[npt.NDArray[np.bool_] | None] = []
        self._weighted: tuple[float, list[FloatArray]] = (math.nan, [])
        # Per bucket, each (row, level) read, once, by row, and where each row's reads
        # start: the rows a change of rates reaches.
        self._reads: list[tuple[IntArray, IntArray]] = []
        for members in buckets_of(lengths):
            width = int(lengths[members].max())
            index = np.zeros((members.size, width), dtype=np.int64)
            observed = np.zeros((members.size, width))
            mask = np.zeros((members.size, width), dtype=bool)
            for row, member in enumerate(members):
                length = lengths[member]
                index[row, :length] = inverse[offsets[member]:offsets[member] + length]
                observed[row, :length] = observed_all[member]
                observed[row, length:] = observed_all[member][-1] if length else 0.0
                mask[row, :length] = True
            initial = np.array([initial_all[m] for m in members])
            self.buckets.append((members, index, observed, mask, initial))
            # Padding reads an extra level whose increment is 0, and the residuals of a
            # bucket are read where its samples are (all of it: None).
            self._padded.append(np.where(mask, index, self.levels.size))
            self._samples.append(None if mask.all() else np.flatnonzero(mask.ravel()))
            self._padding.append(None if mask.all() else ~mask)
            # Every row reads the padding level too (never changed): no row reads nothing.
            read = np.unique(np.arange(members.size)[:, None] * (self.levels.size + 1)
                             + np.c_[self._padded[-1], np.full(members.size, self.levels.size)])
            rows, levels = np.divmod(read, self.levels.size + 1)
            self._reads.append((levels, np.r_[0, np.flatnonzero(np.diff(rows)) + 1]))
            if gains is not None:
                gain = np.ones((members.size, width))
                for row, member in enumerate(members):
                    gain[row, :lengths[member]] = gains[int(member)]
                self.gains.append(gain)

    def increments(self, rate: RateFunction) -> list[FloatArray]:
        """Per bucket, ``dt rate(v_{k-tau})`` with padding set to zero."""
        per_level = self._per_level(rate)
        return [self._increments(bucket, per_level) for bucket in range(len(self.buckets))]

    def residuals(self, rate: RateFunction, beta: float = 0.0) -> FloatArray:
        """Prediction errors ``Z`` of every sample, concatenated (regret-regression form)."""
        return self.evaluate([(rate, beta)])[0].residuals

    def residuals_of_many(self, maps: Sequence[tuple[RateFunction, float]]
                          ) -> list[FloatArray]:
        """Return the residuals of several maps (:meth:`evaluate`), each as :meth:`residuals`."""
        return [evaluation.residuals for evaluation in self.evaluate(maps)]

    def evaluate(self, maps: Sequence[tuple[RateFunction, float]],
                 base: Evaluation | None = None) -> list[Evaluation]:
        """
        Return the residuals of several maps, each as :meth:`residuals` gives them, bit for bit.

        ``maps``: each map's rate function and its ``beta``.
        ``base``: an earlier evaluation to start from.
        """
        per_level = [self._per_level(rate) for rate, _ in maps]
        out: dict[int, Evaluation] = {}
        groups: dict[bytes, list[int]] = {}
        for index, (_, beta) in enumerate(maps):
            # Bits, not values: 0.0 and -0.0 go through different operations.
            groups.setdefault(np.float64(beta).tobytes(), []).append(index)
        for key, members in groups.items():
            beta = maps[members[0]][1]
            stacked = np.stack([per_level[index] for index in members])
            changed = None if base is None or np.float64(base.beta).tobytes() != key else \
                stacked.view(np.int64) != base.per_level.view(np.int64)
            blocks = [self._bucket_grids(bucket, stacked, beta, base, changed)
                      for bucket in range(len(self.buckets))]
            residuals = self._flatten(blocks)
            for row, index in enumerate(members):
                out[index] = Evaluation(maps[index][1], per_level[index],
                                        tuple(block[row] for block in blocks), residuals[row])
        return [out[index] for index in range(len(maps))]

    def _bucket_grids(self, bucket: int, stacked: FloatArray, beta: float,
                      base: Evaluation | None, changed: npt.NDArray[np.bool_] | None
                      ) -> FloatArray:
        """Return a bucket's residual grids, one per row of levels, from ``base`` where it can."""
        if base is not None and changed is not None:
            levels, starts = self._reads[bucket]
            # Per row of levels, the rows of the bucket that read a level whose rate changed.
            maps, rows = np.nonzero(np.logical_or.reduceat(changed[:, levels], starts, axis=1))
            if maps.size < stacked.shape[0] * starts.size:
                out = np.empty((stacked.shape[0],) + base.grids[bucket].shape)
                out[...] = base.grids[bucket]
                if maps.size:
                    out[maps, rows] = self._bucket_residuals(bucket, stacked, beta,
                                                             (maps, rows))
                return out
        return self._bucket_residuals(bucket, stacked, beta)

    def _flatten(self, blocks: Sequence[FloatArray]) -> FloatArray:
        """Return the residuals of the samples, bucket after bucket, one row per map."""
        flat = [block.reshape(block.shape[0], -1) for block in blocks]
        parts = [grid if samples is None else np.take(grid, samples, axis=1)
                 for grid, samples in zip(flat, self._samples)]
        # A copy even of one whole bucket: the residuals never share the grids' memory.
        return parts[0] if len(parts) == 1 and parts[0] is not flat[0] else \
            np.concatenate(parts, axis=1)

    def _per_level(self, rate: RateFunction) -> FloatArray:
        """Return ``dt rate`` of every level, then 0 for the padding."""
        return np.append(self.dt * rate(self.levels), 0.0)

    def _increments(self, bucket: int, per_level: FloatArray,
                    rows: tuple[IntArray, IntArray] | None = None) -> FloatArray:
        """Return a bucket's increments, padding set to zero."""
        padded, padding = self._padded[bucket], self._padding[bucket]
        gain = self.gains[bucket] if self.gains else None
        # take reads the same numbers as fancy indexing, in a fraction of the time.
        if rows is None:
            q = np.take(per_level, padded, axis=-1)
        else:
            q = np.take(per_level.ravel(),
                        rows[0][:, None] * per_level.shape[-1] + padded[rows[1]])
            padding = None if padding is None else padding[rows[1]]
            gain = None if gain is None else gain[rows[1]]
        if self.pole != 0.0:
            p = self.pole
            q = first_order(q, p, 1.0 - p, q[..., 0])
            # The lag runs on past a row's end: zero it there (q is a new array).
            if padding is not None:
                np.copyto(q, 0.0, where=padding)
        if gain is not None:
            q *= gain
        return q

    def _bucket_residuals(self, bucket: int, per_level: FloatArray, beta: float,
                          rows: tuple[IntArray, IntArray] | None = None) -> FloatArray:
        """Return a bucket's residuals, one row per experiment (rows as :meth:`_increments`)."""
        q = self._increments(bucket, per_level, rows)
        _, _, observed, _, initial = self.buckets[bucket]
        if rows is not None:
            observed, initial = observed[rows[1]], initial[rows[1]]
        target = np.empty_like(q)
        if beta == 0.0:
            np.add(initial[:, None], np.cumsum(q, axis=-1), out=target)
        else:
            # A finite-difference Jacobian varies beta in one column of several: keep
            # beta times the angles (read once, so the pair stays whole across threads).
            cached = self._weighted
            if cached[0] != beta:
                cached = (beta, [beta * b[2] for b in self.buckets])
                self._weighted = cached
            a = 1.0 - beta
            drive = q * a
            drive += cached[1][bucket] if rows is None else cached[1][bucket][rows[1]]
            state = first_order(drive, a, 1.0, initial)
            # Predicted from the state before: the start for the first sample.
            np.add(initial[:, None], q[..., :1], out=target[..., :1])
            np.add(state[..., :-1], q[..., 1:], out=target[..., 1:])
        np.subtract(observed, target, out=target)
        return target

    def simulation_mae(self, rate: RateFunction) -> float:
        """Mean absolute simulation error over all predicted samples, degrees."""
        return float(np.mean(np.abs(self.residuals(rate, 0.0))))

    def mean_experiment_sse(self, rate: RateFunction) -> float:
        """Mean over experiments of the summed squared simulation error (West et al.)."""
        return float(np.sum(self.residuals(rate, 0.0) ** 2) / len(self.experiments))


@dataclass(frozen=True, eq=False)
class Evaluation:
    """
    One map's residuals, kept whole so that later evaluations can start from them.

    Attributes
    ----------
    per_level : FloatArray
        ``dt rate`` of every level, then 0 for the padding.
    grids : tuple of FloatArray
        Per bucket, the residuals, one row per experiment (never changed once made).
    residuals : FloatArray
        One residual per predicted sample.

    """

    beta: float
    per_level: FloatArray
    grids: tuple[FloatArray, ...]
    residuals: FloatArray


@dataclass(frozen=True, eq=False)
class MapFit(Generic[MapT]):
    """
    A fitted static map.

    Attributes
    ----------
    method : str
        ``rr``, ``oe``, ``points`` (fitted to the per-level speeds) or ``increments`` (least
        squares on the one-step angle increments, routine operation).
    beta : float
        Regret-regression gain (0 for ``oe``; 1 for ``increments``, whose one-step prediction
        starts from every measured angle).

    """

    static_map: MapT
    method: Literal['rr', 'oe', 'points', 'increments']
    beta: float
    cost: float
    standard_errors: dict[str, float] = field(default_factory=dict)
    evaluations: int = 0
    starts: int = 1


def covariance_errors(jacobian: FloatArray, cost: float, samples: int) -> FloatArray:
    """Return standard errors from a least-squares Jacobian and cost (half the SSE)."""
    parameters = jacobian.shape[1]
    variance = 2.0 * cost / max(samples - parameters, 1)
    try:
        covariance = variance * np.linalg.pinv(jacobian.T @ jacobian)
    except np.linalg.LinAlgError:
        return np.full(parameters, np.inf)
    return np.sqrt(np.clip(np.diag(covariance), 0.0, None))

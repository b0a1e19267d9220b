"""
Experiments arranged for fast residual evaluation, and what a fit returns.

Every experiment predicts its angles from its initial state with
``pred_k = x_{k-1} + dt w_k``, ``Z_k = y_k - pred_k`` and
``x_k = pred_k + beta Z_k`` (docs/methods.md section 2), where ``w_k`` is
``rate(v_{k-tau})``, passed through the first-order valve lag when there is one. The recursion is a
first-order filter, so each residual evaluation is a few numpy and ``first_order``
calls over all experiments at once (experiments of similar length share one
padded 2-D array), and the map is evaluated once per distinct command level.

"""

from __future__ import annotations

from dataclasses import dataclass, field
import math
from typing import Callable, Generic, get_args, Literal, Sequence, TypeVar

from hydro_sdp.core.arrays import FloatArray, IntArray
from hydro_sdp.core.errors import DataError
from hydro_sdp.core.identification.experiment import Experiment
from hydro_sdp.core.model.first_order import first_order
from hydro_sdp.core.model.static_maps import StaticMap
from hydro_sdp.core.model.timing import delayed_at
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


class FitData:
    """
    Experiments arranged for fast residual evaluation.

    Parameters
    ----------
    experiments : sequence of Experiment
        The experiments.
    delay : int
        Delay, samples.
    dt : float
        Sample period, s.
    lag : float
        Valve lag time constant, s (0: none); each experiment's lag starts in
        steady state at its first delayed command.
    gains : sequence of FloatArray or None
        Per experiment, a factor on the speed of each predicted sample (the
        stroke geometry at the measured angle before it); default: 1.

    """

    def __init__(self, experiments: Sequence[Experiment], delay: int, dt: float,
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
        # Pad experiments of similar length (same power of two) into one 2-D block.
        sizes = 2 ** np.ceil(np.log2(np.maximum(lengths, 1))).astype(int)
        offsets = np.r_[0, np.cumsum(lengths)]
        self.buckets: list[tuple[IntArray, IntArray, FloatArray, npt.NDArray[np.bool_],
                                 FloatArray]] = []
        self.gains: list[FloatArray] = []
        self._padded: list[IntArray] = []
        self._flat: list[IntArray | None] = []
        self._weighted: tuple[float, list[FloatArray]] = (math.nan, [])
        for size in np.unique(sizes):
            members = np.flatnonzero(sizes == size)
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
            # bucket are read at the flat positions of its samples (all of them: None).
            self._padded.append(np.where(mask, index, self.levels.size))
            self._flat.append(None if mask.all() else np.flatnonzero(mask.ravel()))
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
        """
        Prediction errors ``Z`` of every sample, concatenated (regret-regression form).

        Parameters
        ----------
        rate : callable
            The map, commands to deg/s.
        beta : float
            Gain on the state residuals (0: simulation error).

        Returns
        -------
        FloatArray
            One residual per predicted sample.

        """
        return self.residuals_of_many([(rate, beta)])[0]

    def residuals_of_many(self, maps: Sequence[tuple[RateFunction, float]]
                          ) -> list[FloatArray]:
        """
        The residuals of several maps, each as :meth:`residuals` gives them, bit for bit.

        Maps of the same ``beta`` (the columns of a finite-difference Jacobian but the
        one of ``beta``) run through each numpy operation together, one row of a 3-D
        block each: the same operations on the same numbers, a few calls for all.

        Parameters
        ----------
        maps : sequence of (callable, float)
            Each map's rate function and its ``beta``.

        Returns
        -------
        list of FloatArray
            Per map, one residual per predicted sample.

        """
        per_level = [self._per_level(rate) for rate, _ in maps]
        out = [np.empty(self.samples) for _ in maps]
        groups: dict[bytes, list[int]] = {}
        for index, (_, beta) in enumerate(maps):
            # Bits, not values: 0.0 and -0.0 go through different operations.
            groups.setdefault(np.float64(beta).tobytes(), []).append(index)
        for members in groups.values():
            stacked = np.stack([per_level[index] for index in members])
            done = 0
            for bucket, flat in enumerate(self._flat):
                grid = self._bucket_residuals(bucket, stacked, maps[members[0]][1])
                rows = grid.reshape(len(members), -1)
                values = rows if flat is None else rows[:, flat]
                for row, index in enumerate(members):
                    out[index][done:done + values.shape[1]] = values[row]
                done += values.shape[1]
        return out

    def _per_level(self, rate: RateFunction) -> FloatArray:
        """Return ``dt rate`` of every level, then 0 for the padding."""
        return np.append(self.dt * rate(self.levels), 0.0)

    def _increments(self, bucket: int, per_level: FloatArray) -> FloatArray:
        """Return a bucket's increments, padding set to zero (one block per row of levels)."""
        q = per_level[..., self._padded[bucket]]
        if self.pole != 0.0:
            p = self.pole
            q = np.where(self.buckets[bucket][3], first_order(q, p, 1.0 - p, q[..., 0]), 0.0)
        if self.gains:
            q = q * self.gains[bucket]
        return q

    def _bucket_residuals(self, bucket: int, per_level: FloatArray, beta: float) -> FloatArray:
        """Return a bucket's residuals, one row per experiment (one block per row of levels)."""
        q = self._increments(bucket, per_level)
        _, _, observed, _, initial = self.buckets[bucket]
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
            drive += cached[1][bucket]
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
class MapFit(Generic[MapT]):
    """
    A fitted static map.

    Parameters
    ----------
    static_map : StaticMap
        The map.
    method : str
        ``rr``, ``oe``, ``points`` (fitted to the per-level speeds) or ``increments``
        (least squares on the one-step angle increments, routine operation).
    beta : float
        Regret-regression gain (0 for ``oe``; 1 for ``increments``, whose one-step
        prediction starts from every measured angle).
    cost : float
        Sum of squared residuals at the optimum.
    standard_errors : dict
        Standard error of each parameter, by model-file name.
    evaluations : int
        Objective evaluations used.
    starts : int
        Starting points tried.

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


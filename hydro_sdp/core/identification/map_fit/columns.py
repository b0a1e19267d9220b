"""Finite-difference Jacobians of the residuals, every column in one pass (methods 2.3)."""

from __future__ import annotations

import inspect
from typing import Callable, Iterable, TypeVar

from hydro_sdp.core.arrays import FloatArray
from hydro_sdp.core.identification.map_fit.data import Evaluation, FitData, RateFunction
import numpy as np
from scipy.optimize import least_squares

#: A map family's parameters to its rate function and its ``beta``.
ParametrisedMap = Callable[[FloatArray], tuple[RateFunction, float]]
Result = TypeVar('Result')
#: scipy 1.16 and later evaluate a Jacobian's points through ``workers``; an older scipy
#: (a distribution's package, as rosdep installs it) fits the same, one column at a time.
TAKES_WORKERS = 'workers' in inspect.signature(least_squares).parameters


class BatchedResiduals:
    """
    The residuals of a parametrised map, and a map-like that evaluates many points at once.

    Pass the object as the residual function of ``least_squares`` and its
    :attr:`options` (``workers=map_points``) as keyword arguments.
    """

    def __init__(self, data: FitData, parametrised: ParametrisedMap) -> None:
        self.data = data
        self.parametrised = parametrised
        self._ready: dict[bytes, FloatArray] = {}
        # The last point evaluated alone: scipy takes its Jacobian there.
        self._last: Evaluation | None = None

    def __call__(self, x: FloatArray) -> FloatArray:
        """Return the residuals at ``x`` (evaluated already while :meth:`map_points` runs)."""
        ready = self._ready.pop(_key(x), None)
        if ready is not None:
            return ready
        self._last = self.data.evaluate([self.parametrised(x)], self._last)[0]
        return self._last.residuals

    @property
    def options(self) -> dict[str, Callable[..., object]]:
        """Keyword arguments for ``least_squares``: ``workers`` where scipy takes it."""
        return {'workers': self.map_points} if TAKES_WORKERS else {}

    def map_points(self, function: Callable[[FloatArray], Result],
                   points: Iterable[FloatArray]) -> list[Result]:
        """
        Apply ``function`` to every point, the residuals of all evaluated in one pass.

        ``function``: scipy's wrapper of this object.
        ``points``: the points (a Jacobian's: one parameter moved in each).
        Returns: ``function`` of each point, in order.
        """
        points = [np.array(point, dtype=np.float64) for point in points]
        evaluated = self.data.evaluate([self.parametrised(p) for p in points], self._last)
        self._ready = {_key(point): e.residuals for point, e in zip(points, evaluated)}
        try:
            return [function(point) for point in points]
        finally:
            self._ready = {}


def _key(x: FloatArray) -> bytes:
    return np.asarray(x, dtype=np.float64).tobytes()


def forward_jacobian(data: FitData, parametrised: ParametrisedMap,
                     x: FloatArray) -> FloatArray:
    """
    Return the forward-difference Jacobian of the residuals at ``x``, all columns in one pass.

    Returns: one row per residual, one column per parameter; the steps are
    ``1e-6 max(|x_i|, 1e-3)``.
    """
    points, steps = [x], []
    for i in range(x.size):
        step = 1e-6 * max(abs(x[i]), 1e-3)
        shifted = x.copy()
        shifted[i] += step
        points.append(shifted)
        steps.append(step)
    base, *moved = data.residuals_of_many([parametrised(point) for point in points])
    return np.column_stack([(residuals - base) / step for residuals, step in zip(moved, steps)])

"""
The held-out simulation error the decision weighs: windows that start from the measured angle.

A whole record's simulation error drifts: a model still wrong in one way (its map's
slope) integrates that error over the record, and a candidate that corrects another
(the dead-zone) can leave it larger, while one that is wrong can lower it by chance
(an angle factor that happens to turn the drift back). The decision therefore compares
the models over windows of :data:`WINDOW_SECONDS`, each simulated afresh from the
measured angle at its start (:func:`~hydro_sdp.core.model.windows.simulate_windows`):
long enough for what an effect integrates (a stop held for seconds, a lag over a move,
a pump's share), short enough that one error does not hide another. Two models are
compared over the same samples, from the later of the two samples at which their states
no longer depend on what came before the record (docs/methods.md sections 3.8 and 8.4).
The figures the diagnosis reports stay those of whole records (:func:`~.residuals.mae`).

"""

from __future__ import annotations

from typing import Sequence

from hydro_sdp.core.diagnosis.residuals import Run
from hydro_sdp.core.identification.evaluation import first_compared
from hydro_sdp.core.model.joint_model import JointModel
from hydro_sdp.core.model.windows import simulate_windows
import numpy as np

#: Length of the windows simulated from the measured angle, s.
WINDOW_SECONDS = 2.0


class WindowErrors:
    """
    Simulation errors of models over held-out runs, each simulation made once.

    Parameters
    ----------
    runs : sequence of Run
        Held-out runs.

    """

    def __init__(self, runs: Sequence[Run]) -> None:
        self.runs = runs
        self._cache: dict[tuple[int, int, int, float | None], float] = {}
        self._models: dict[int, JointModel] = {}

    def _error(self, model: JointModel, index: int, start: int, seconds: float | None) -> float:
        key = (id(model), index, start, seconds)
        if key not in self._cache:
            # Holding the model keeps its id from being reused while it is cached.
            self._models[id(model)] = model
            run = self.runs[index]
            record = run.record
            width = len(record) if seconds is None else max(1, int(round(seconds / run.dt)))
            simulated = simulate_windows(model, record.v, record.y, run.dt,
                                         list(range(start, len(record) - 1, width)),
                                         v_before=float(record.v[0]), exogenous=run.exogenous)
            self._cache[key] = float(np.mean(np.abs(record.y[start:] - simulated[start:])))
        return self._cache[key]

    def compare(self, models: Sequence[JointModel],
                seconds: float | None = WINDOW_SECONDS) -> list[float]:
        """
        Return each model's mean absolute simulation error, averaged per record, deg.

        Parameters
        ----------
        models : sequence of JointModel
            The models compared, over the same samples: from the later of the samples
            at which each model's state no longer depends on the past.
        seconds : float or None
            Window length, s; None: one window, the whole record from that sample.

        Returns
        -------
        list[float]
            One error per model, degrees.

        """
        errors = np.zeros((len(self.runs), len(models)))
        for i, run in enumerate(self.runs):
            start = max(first_compared(model, run.dt, run.record) for model in models)
            for j, model in enumerate(models):
                errors[i, j] = self._error(model, i, start, seconds)
        return errors.mean(axis=0).tolist()

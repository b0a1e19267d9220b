"""Data shared by the detectors of one iteration, and their scoring (methods 8.2)."""

from __future__ import annotations

import math
from typing import Callable, Sequence

from hydro_sdp.core.diagnosis.naming import Naming
from hydro_sdp.core.diagnosis.reduction import reduction_test
from hydro_sdp.core.diagnosis.residuals import (
    BLOCK_SECONDS, block_sums, MIN_GAIN, Run, velocity_residuals)
from hydro_sdp.core.diagnosis.results import Candidate, Trial
from hydro_sdp.core.errors import DataError, HydroSdpError
from hydro_sdp.core.identification.experiment import split_long, thin
from hydro_sdp.core.identification.map_fit import FitData
from hydro_sdp.core.identification.segmentation import (
    estimate_rest_command, segment_records, Segmentation)
from hydro_sdp.core.model.joint_model import JointModel
import numpy as np
from scipy.optimize import minimize_scalar


class Context:
    """
    The model under test, the runs and what every detector needs from them.

    ``max_delay``: largest delay considered, samples.
    ``naming``: what the SDP analysis of the model's misses found (None: not analysed).
    """

    def __init__(self, model: JointModel, runs: Sequence[Run], max_delay: int,
                 naming: Naming | None = None) -> None:
        self.model = model
        self.naming = naming if naming is not None else Naming(None)
        self.runs = runs
        self.dt = runs[0].dt
        self.max_delay = max_delay
        self.block = max(2, int(round(BLOCK_SECONDS / self.dt)))
        self.base = velocity_residuals(model, runs)
        records = [r.record for r in runs]
        self.segmentation: Segmentation | None
        try:
            self.segmentation = segment_records(records, max_delay=max_delay)
        except HydroSdpError:
            # Records that never rest hold no experiments; the candidates that start from
            # them start from the model instead.
            self.segmentation = None
        levels = np.concatenate([r.record.v for r in runs])
        if model.dead_zone is not None:
            self.rest = model.rest_command
        elif self.segmentation is not None:
            self.rest = self.segmentation.rest
        else:
            self.rest = estimate_rest_command([(r.v, r.y) for r in records],
                                              input_limits=model.input_limits)
        self.scale = max(float(np.max(np.abs(levels - self.rest))), 1e-9)

    def fit_data(self, delay: int) -> FitData:
        """Return the experiments as regret-regression data at ``delay`` samples."""
        if self.segmentation is None or not self.segmentation.experiments:
            raise DataError('the records hold no experiments (the command never rests)')
        pieces = split_long(self.segmentation.experiments, 3000, self.max_delay)
        return FitData(thin(pieces, 60_000), delay, self.dt)

    def squared_residual(self, model: JointModel) -> float:
        """Return the squared velocity residual of ``model`` over whole blocks, deg^2."""
        return float(block_sums(velocity_residuals(model, self.runs), self.block).sum())

    def score(self, effect: str, candidate: JointModel, parameters: dict[str, object],
              evidence: str) -> Trial:
        """Compare ``candidate`` with the model under test on the estimation runs."""
        reduction = reduction_test(self.base, velocity_residuals(candidate, self.runs),
                                   self.block)
        significant = reduction.significant and reduction.gain > MIN_GAIN
        return Candidate(effect, True, reduction.gain, reduction.z, significant, parameters,
                         evidence, p_value=reduction.p_value), candidate

    def fit_scalar(self, build: Callable[[float], JointModel], bounds: tuple[float, float],
                   log: bool = False) -> float:
        """Return the parameter in ``bounds`` whose model has the least squared residual."""
        def cost(x: float) -> float:
            return self.squared_residual(build(math.exp(x) if log else x))
        low, high = (math.log(bounds[0]), math.log(bounds[1])) if log else bounds
        result = minimize_scalar(cost, bounds=(low, high), method='bounded',
                                 options={'xatol': 1e-3})
        return math.exp(result.x) if log else float(result.x)

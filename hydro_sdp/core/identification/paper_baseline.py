"""
The first paper's identification as a plain baseline: eq. (5) by simplex on the output error.

The reasoning is in docs/methods.md section 13.7.

"""

from __future__ import annotations

from typing import Sequence

from hydro_sdp.core.identification.change_windows import lagged_residual
from hydro_sdp.core.identification.delay import level_speeds
from hydro_sdp.core.identification.experiment import split_long
from hydro_sdp.core.identification.identify import PIECE_SAMPLES
from hydro_sdp.core.identification.map_fit import fit_sdp, FitData
from hydro_sdp.core.identification.segmentation import check_records, segment_records
from hydro_sdp.core.model.joint_model import JointModel
from hydro_sdp.core.model.records import Record
from hydro_sdp.core.model.sample_period import whole_samples_seconds


def paper_model(records: Sequence[Record], *, max_delay: float = 0.5,
                rest: float | None = None) -> JointModel:
    """
    Identify eq. (5) with a pure delay by the paper's output-error simplex fit.

    ``max_delay``: largest delay considered, s.
    ``rest``: rest command (default: as :func:`~.segmentation.segment_records`).
    """
    dt = check_records(records)
    most = max(2, int(round(max_delay / dt)))
    segmentation = segment_records(records, max_delay=most, rest=rest)
    pieces = split_long(segmentation.experiments, PIECE_SAMPLES, most)
    delay = min(range(1, most + 1), key=lambda d: lagged_residual(pieces, d, 0.0))
    points = level_speeds(pieces, delay, dt, rest=segmentation.rest)
    fit = fit_sdp(FitData(pieces, delay, dt), points, segmentation.rest, method='oe', starts=2)
    low, high = segmentation.end_stops
    limits = (low, high) if low is not None and high is not None else None
    return JointModel(records[0].joint or 'joint', fit.static_map,
                      whole_samples_seconds(delay, dt), angle_limits=limits)

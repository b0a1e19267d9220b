"""
What ``identify`` found (:class:`Identification`), and the stages it goes through.

The reasoning is in docs/methods.md section 13.

"""

from __future__ import annotations

from dataclasses import dataclass, field
import enum
from typing import get_args, Literal

from hydro_sdp.core.errors import DataError
from hydro_sdp.core.identification.delay import DelayEstimate, LevelSpeed
from hydro_sdp.core.identification.effect_check import HeldOut
from hydro_sdp.core.identification.family_choice import fit_family, FittedKind, KindScore
from hydro_sdp.core.identification.held_out import Judgement
from hydro_sdp.core.identification.limits import CommandRange
from hydro_sdp.core.identification.map_fit import FitData, FitMethod, MapFit
from hydro_sdp.core.identification.segmentation import Segmentation
from hydro_sdp.core.model.joint_model import JointModel
from hydro_sdp.core.model.static_maps import SdpMap, StaticMap
from hydro_sdp.core.model.timing import SamplePeriod

#: How the records were identified: from experiments with held levels, or from routine
#: operation (commands changing every control period).
Route = Literal['experiments', 'routine']
ROUTES: tuple[Route, ...] = get_args(Route)


class IdentifyStage(enum.IntEnum):
    """The stages of ``identify``, in order (their number counts progress)."""

    SEGMENTING = 0
    DELAY = 1
    MAP = 2
    FAMILIES = 3

    @property
    def label(self) -> str:
        """Return what the stage does, for a progress bar."""
        return ('segmenting', 'estimating the delay', 'fitting the static map',
                'comparing map families on held-out experiments')[self]


@dataclass(frozen=True, eq=False)
class Identification:
    """
    Everything ``identify`` found.

    Attributes
    ----------
    sample_period : float
        Sample period of the records, s.
    points : tuple[LevelSpeed, ...]
        Speed of every experiment and command level (routine operation: the speed along the delayed
        command estimated by the SDP smoother).
    fit : MapFit
        The chosen map's fit.
    mae : float
        Mean absolute simulation error of the model on all experiments, degrees.
    effect_checks : tuple[HeldOut, ...]
        Held-out errors without and with each effect identify proposed by itself (``valve_lag``,
        ``stroke_geometry``), and whether it was kept.
    route : str
        ``experiments`` or ``routine`` (:data:`ROUTES`).
    commands : CommandRange or None
        The commands seen and where the model's limits come from.
    family : Judgement or None
        How the family was chosen (None when it was asked for by name).
    fit_data, sdp_map, method
        The map's data, eq. (5)'s fit and the method, for :meth:`family_map`.

    """

    model: JointModel
    sample_period: SamplePeriod
    delay: DelayEstimate
    segmentation: Segmentation
    points: tuple[LevelSpeed, ...]
    fit: MapFit[StaticMap]
    comparison: tuple[KindScore, ...]
    mae: float
    effect_checks: tuple[HeldOut, ...] = ()
    route: Route = 'experiments'
    commands: CommandRange | None = None
    family: Judgement | None = None
    fit_data: FitData | None = field(default=None, repr=False)
    sdp_map: SdpMap | None = field(default=None, repr=False)
    method: FitMethod = 'rr'

    def family_map(self, kind: FittedKind) -> StaticMap:
        """Return the map of family ``kind`` fitted on the same data at the same timing."""
        if kind == self.model.kind:
            return self.fit.static_map
        if self.fit_data is None or self.sdp_map is None:
            raise DataError(f'no {kind} map to fit: this identification kept no fit data')
        return fit_family(kind, self.fit_data, self.points, self.segmentation.rest,
                          self.method, self.sdp_map).static_map

    @property
    def alpha(self) -> tuple[float, ...] | None:
        """Return the paper's ``alpha_1..alpha_6`` at the records' sample period (``sdp``)."""
        if self.model.kind != 'sdp':
            return None
        return self.model.alpha(self.sample_period)

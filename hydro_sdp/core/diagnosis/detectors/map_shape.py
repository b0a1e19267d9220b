"""Detectors of the static map's shape: dead-zone, velocity saturation, asymmetry (methods 8.2)."""

from __future__ import annotations

from abc import abstractmethod
from typing import ClassVar, Literal

from hydro_sdp.core.diagnosis.context import Context
from hydro_sdp.core.diagnosis.detectors.base import Detector
from hydro_sdp.core.diagnosis.refit import map_features, map_parameters, refit_map
from hydro_sdp.core.diagnosis.results import Candidate, Trial
from hydro_sdp.core.model.joint_model import JointModel
from hydro_sdp.core.model.static_maps import PowerSatMap, SdpMap


class MapShapeDetector(Detector):
    """An effect of the map's shape: the static map refitted with one more feature."""

    feature = 'command'
    state = 'command'
    #: The map feature the effect adds (a field of :class:`~.refit.Features`).
    adds: ClassVar[Literal['dead_zone', 'saturation', 'asymmetric']]

    def fit(self, context: Context) -> Trial:
        """Refit the map with the feature (keeping its other features) and score it."""
        features = map_features(context.model.static_map)
        # A dead-zone's edges are refitted whether or not the map has one (they may be
        # wrong); saturation and a side each are only ever added.
        if getattr(features, self.adds) and self.adds != 'dead_zone':
            return Candidate(self.word, False), None
        candidate = refit_map(context, features._replace(**{self.adds: True}))
        return context.score(self.word, candidate, map_parameters(candidate),
                             self.finding(candidate))

    @abstractmethod
    def finding(self, candidate: JointModel) -> str:
        """Return what the refitted model ``candidate`` shows of the data, the evidence."""


class DeadZoneDetector(MapShapeDetector):
    """The joint stays still for small commands: refit the map with a dead-zone."""

    word = 'dead_zone'
    description = 'the joint stays still where the model moves'
    remedy = "the map's edges refitted (a linear model becomes `sdp_dz`)"
    adds = 'dead_zone'

    def finding(self, candidate: JointModel) -> str:
        """Return the dead-zone found."""
        low, high = candidate.dead_zone or (0.0, 0.0)
        return (f'the joint stays still for commands in [{low:.4g}, {high:.4g}] '
                'where the model moves it')


class VelocitySaturationDetector(MapShapeDetector):
    """The speed levels off: refit the map as an SDP or a saturating power-law map."""

    word = 'velocity_saturation'
    description = "the speed levels off, the model's keeps growing"
    remedy = 'an `sdp_dz` or linear map becomes `sdp` or `power_sat`'
    adds = 'saturation'

    def finding(self, candidate: JointModel) -> str:
        """Return the saturation speeds found."""
        static_map = candidate.static_map
        assert isinstance(static_map, (SdpMap, PowerSatMap))
        speeds = static_map.saturation_velocity
        return (f'the speed levels off at {speeds[0]:.3g} and {speeds[1]:.3g} '
                'deg/s while the model keeps growing with the command')


class AsymmetryDetector(MapShapeDetector):
    """The two directions differ: refit the map with a side each."""

    word = 'asymmetry'
    description = 'the two directions differ, the model treats them alike'
    remedy = 'the two sides fitted separately'
    adds = 'asymmetric'

    def finding(self, candidate: JointModel) -> str:
        """Return the evidence of asymmetry."""
        return 'the two directions move at different speeds for the same command size'

"""Detectors of the static map's shape: dead-zone, velocity saturation, asymmetry."""

from __future__ import annotations

from hydro_sdp.core.diagnosis.context import Context
from hydro_sdp.core.diagnosis.detectors.base import Detector
from hydro_sdp.core.diagnosis.refit import map_features, map_parameters, refit_map
from hydro_sdp.core.diagnosis.results import Candidate, Trial
from hydro_sdp.core.static_maps import SdpMap


class DeadZone(Detector):
    """The joint stays still for small commands: refit the map with a dead-zone."""

    word = 'dead_zone'
    description = 'the joint stays still where the model moves'
    remedy = "the map's edges refitted (a linear model becomes `sdp_dz`)"
    feature = 'command'

    def fit(self, context: Context) -> Trial:
        """Refit the map with a dead-zone (keeping its other features) and score it."""
        features = map_features(context.model.static_map)
        candidate = refit_map(context, features._replace(dead_zone=True))
        low, high = candidate.dead_zone or (0.0, 0.0)
        return context.score(self.word, candidate, map_parameters(candidate),
                             f'the joint stays still for commands in [{low:.4g}, {high:.4g}] '
                             'where the model moves it')


class VelocitySaturation(Detector):
    """The speed levels off: refit the map as an SDP map."""

    word = 'velocity_saturation'
    description = "the speed levels off, the model's keeps growing"
    remedy = 'an `sdp_dz` or linear map becomes `sdp`'
    feature = 'command'

    def fit(self, context: Context) -> Trial:
        """Refit the map with saturation, if it has none, and score it."""
        features = map_features(context.model.static_map)
        if features.saturation:
            return Candidate(self.word, False), None
        candidate = refit_map(context, features._replace(saturation=True))
        static_map = candidate.static_map
        assert isinstance(static_map, SdpMap)
        speeds = static_map.saturation_velocity
        return context.score(self.word, candidate, map_parameters(candidate),
                             f'the speed levels off at {speeds[0]:.3g} and {speeds[1]:.3g} '
                             'deg/s while the model keeps growing with the command')


class Asymmetry(Detector):
    """The two directions differ: refit the map with a side each."""

    word = 'asymmetry'
    description = 'the two directions differ, the model treats them alike'
    remedy = 'the two sides fitted separately'
    feature = 'command'

    def fit(self, context: Context) -> Trial:
        """Refit the map with separate sides, if it has one for both, and score it."""
        features = map_features(context.model.static_map)
        if features.asymmetric:
            return Candidate(self.word, False), None
        candidate = refit_map(context, features._replace(asymmetric=True))
        return context.score(self.word, candidate, map_parameters(candidate),
                             'the two directions move at different speeds for the same '
                             'command size')

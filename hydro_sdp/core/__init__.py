"""
The numerical core of hydro_sdp: numpy and scipy only, no ROS, no clock, no logging.

The names users need most are re-exported here.

"""

from hydro_sdp.core.errors import (
    BagError, ConfigurationError, DataError, HydroSdpError, ModelFileError)
from hydro_sdp.core.model.effects import (
    AngleDependentVelocity, Backlash, DirectionDependentDelay, Effect, ValveLag)
from hydro_sdp.core.model.joint_model import JointModel
from hydro_sdp.core.model.records import Record
from hydro_sdp.core.model.simulation import JointSimulator, simulate
from hydro_sdp.core.model.static_maps import LinearMap, SdpDzMap, SdpMap

__all__ = [
    'AngleDependentVelocity', 'Backlash', 'BagError', 'ConfigurationError', 'DataError',
    'DirectionDependentDelay', 'Effect', 'HydroSdpError', 'JointModel', 'JointSimulator',
    'LinearMap', 'ModelFileError', 'Record', 'SdpDzMap', 'SdpMap', 'ValveLag', 'simulate',
]

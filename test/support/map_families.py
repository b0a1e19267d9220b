"""
Joint models of every map family ``identify`` writes, in the units they come in.

J2 (``sdp``) in volts; a convex valve in signed percent as identified from an
arm's logs (``power_sat`` and ``pwl``, the values ``calibrate`` finds on the
physics plant's arm and on the measured-table joint of
:mod:`support.table_valve_joint`); a polynomial map without a dead-zone; a
piecewise-linear dead-zone and a linear map, in percent resting at 50 and in
signed percent.

"""

from hydro_sdp.core.model.joint_model import JointModel
from hydro_sdp.core.model.static_maps import (
    LinearMap, PolyMap, PowerSatMap, PwlMap, SdpDzMap, SdpMap)

#: One model per family, by kind.
MODELS = {
    'sdp': JointModel('j2', SdpMap((-1.3298, 1.3124), (-29.51, 38.87), (1.356, 1.771)), 0.15,
                      input_limits=(-10.0, 10.0)),
    'power_sat': JointModel('arm', PowerSatMap((-31.52, 16.03), (-47.4, 32.32),
                                               (0.02058, 0.01952), (2.198, 4.529)), 0.39,
                            input_limits=(-100.0, 100.0)),
    'pwl': JointModel('arm', PwlMap((-100.0, -80.0, -60.0, -40.0, -38.57, 38.67, 40.0, 60.0,
                                     80.0, 100.0),
                                    (-27.8, -25.8, -10.4, -0.9, 0.0, 0.0, 1.0, 12.5, 28.7,
                                     31.3)), 0.38, input_limits=(-100.0, 100.0)),
    'poly': JointModel('boom', PolyMap((2.0, 0.04), (2.5, 0.06), (-10.0, 10.0)), 0.1),
    'sdp_dz': JointModel('pwm', SdpDzMap((32.0, 66.0), (0.9, 1.1)), 0.2,
                         input_limits=(0.0, 100.0)),
    'linear': JointModel('pwm', LinearMap(0.5), 0.1, input_limits=(-40.0, 40.0)),
}

"""
A physics-based plant of hydraulic joints, to test identification against.

Structurally unlike the SDP model: a spool valve with overlap, dead time and
lag, orifice flows under a load-sensing pump with flow sharing and relief, a
double-acting cylinder with cushions, a two-pivot linkage, gravity load and a
compliant end stop. Parameters come from ``hydro_sdp/physics/v1`` files
(``config/physics_arm.yaml``, ``config/physics_boom.yaml``).

"""

from hydro_sdp.core.synthetic.physics.machine import PlantRun, PlantSimulator, simulate_plant
from hydro_sdp.core.synthetic.physics.plant import Machine, PHYSICS_FORMAT

__all__ = ['Machine', 'PHYSICS_FORMAT', 'PlantRun', 'PlantSimulator',
           'simulate_plant']

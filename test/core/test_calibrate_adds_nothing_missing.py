"""
calibrate adds no word the joint lacks: the physics arm without its linkage effects.

The physics plant's arm (``config/physics_arm.yaml``) with the cylinder perpendicular to a
long link at mid-stroke (the moment arm varies by about 1 % over the stroke), no cushions
and no payload (:func:`support.spurious_words.without_linkage`): its speed does not change
along the stroke, no load changes, no other joint moves and it has no play. Logged one
duty from stop to stop and back per run (60, 80 and 100 %, validated at 70 %), calibrate
names its lag and nothing else; the same runs of the arm with its linkage get
``stroke_geometry``. The measured-table arm (no linkage either) is held to the same in
``test_calibrate_table_joint.py``; ``test/support/spurious_words.py`` runs both over five
seeds (docs/methods.md section 8.4).

"""

from hydro_sdp.core.calibration import calibrate, CalibrationSettings
import pytest
from support.spurious_words import OWN, physics_records

pytestmark = [pytest.mark.slow(6), pytest.mark.usefixtures('figures_not_drawn')]


@pytest.mark.parametrize('linkage', [False, True])
def test_the_physics_arm_gets_stroke_geometry_only_with_its_linkage(linkage):
    estimation, validation, limits = physics_records(3, estimation=(60, 80, 100),
                                                     validation=(70,), linkage=linkage)
    result = calibrate(estimation, validation, CalibrationSettings(input_limits=limits))
    if linkage:
        assert 'stroke_geometry' in result.effects, result.effects
    else:
        assert set(result.effects) <= OWN and 'valve_lag' in result.effects, result.effects

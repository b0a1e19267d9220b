"""
Identification from routine operation (docs/methods.md section 15).

Closed loops and operators change the command every control period and hold few
levels, if any: :func:`routine_operation` tells such records from experiments
(:mod:`.detect`), and :func:`identify_routine` identifies the map from the
one-step increments against the delayed command (:mod:`.pipeline`).

"""

from hydro_sdp.core.identification.routine.detect import held_share, routine_operation
from hydro_sdp.core.identification.routine.pipeline import identify_routine

__all__ = ['held_share', 'identify_routine', 'routine_operation']

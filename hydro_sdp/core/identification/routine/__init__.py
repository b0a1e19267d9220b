"""Identification from routine operation (docs/methods.md section 15)."""

from hydro_sdp.core.identification.routine.detect import held_share, routine_operation
from hydro_sdp.core.identification.routine.pipeline import identify_routine

__all__ = ['held_share', 'identify_routine', 'routine_operation']

"""
The discrepancy workflow (docs/methods.md section 8, docs/interfaces.md section 5).

Find where a model and measured data disagree, name the missing effect, add it,
and show the gap shrink. The measured commands are replayed through the model
and the velocity residual localises a discrepancy (:mod:`.residuals`); every
word of the vocabulary is a detector that adds its effect and only it, fitted to
the data (:mod:`.detectors`, map shapes refitted by :mod:`.refit`); the search
names the largest significant improvement that also shrinks the validation
error, and repeats until nothing significant is left (:mod:`.search`).

"""

from hydro_sdp.core.diagnosis.detectors import Detector, detector, DETECTORS, VOCABULARY
from hydro_sdp.core.diagnosis.residuals import (
    compare, mae, Run, runs_of, velocity_residuals)
from hydro_sdp.core.diagnosis.results import (
    Candidate, Diagnosis, Feature, Gap, LedgerStep, Signature)
from hydro_sdp.core.diagnosis.search import diagnose

__all__ = ['Candidate', 'compare', 'DETECTORS', 'Detector', 'detector', 'diagnose',
           'Diagnosis', 'Feature', 'Gap', 'LedgerStep', 'mae', 'Run', 'runs_of',
           'Signature', 'velocity_residuals', 'VOCABULARY']

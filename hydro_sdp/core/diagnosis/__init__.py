"""
The discrepancy workflow (docs/methods.md section 8, docs/interfaces.md section 5).

Find where a model and measured data disagree, name the missing effect, add it,
and show the gap shrink. The measured commands are replayed through the model
and the velocity residual localises a discrepancy (:mod:`.residuals`); the SDP
analysis of what the model misses against every state names the words the data
point to and gives their shape (:mod:`.naming`); every word of the vocabulary is a
detector that adds its effect and only it, fitted to the data (:mod:`.detectors`,
map shapes refitted by :mod:`.refit`); each candidate is judged on held-out data by
the size of what it explains and a block bootstrap (:mod:`.decision`,
:mod:`.held_out`, :mod:`.reduction`); the search adds the first accepted and
repeats until none is (:mod:`.search`).

"""

from hydro_sdp.core.diagnosis.detectors import Detector, detector, DETECTORS, VOCABULARY
from hydro_sdp.core.diagnosis.reduction import Reduction, reduction_test
from hydro_sdp.core.diagnosis.residuals import mae, Run, runs_of, velocity_residuals
from hydro_sdp.core.diagnosis.results import (
    Candidate, Diagnosis, Feature, GapTraces, LedgerStep, Signature, StateEvidence)
from hydro_sdp.core.diagnosis.search import diagnose

__all__ = ['Candidate', 'DETECTORS', 'Detector', 'detector', 'diagnose', 'Diagnosis',
           'Feature', 'GapTraces', 'LedgerStep', 'mae', 'Reduction', 'reduction_test', 'Run',
           'runs_of', 'Signature', 'StateEvidence', 'velocity_residuals', 'VOCABULARY']

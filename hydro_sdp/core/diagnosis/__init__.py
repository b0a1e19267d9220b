"""The discrepancy workflow (docs/methods.md section 8, docs/interfaces.md section 5)."""

from hydro_sdp.core.diagnosis.detectors import Detector, detector, DETECTORS, VOCABULARY
from hydro_sdp.core.diagnosis.reduction import Reduction, reduction_test
from hydro_sdp.core.diagnosis.residuals import mae, Run, runs_of, velocity_residuals
from hydro_sdp.core.diagnosis.results import (
    Candidate, Diagnosis, Feature, GapTraces, LedgerStep, Signature, StateEvidence)
from hydro_sdp.core.diagnosis.search import diagnose

__all__ = ['Candidate', 'DETECTORS', 'Detector', 'detector', 'diagnose', 'Diagnosis',
           'Feature', 'GapTraces', 'LedgerStep', 'mae', 'Reduction', 'reduction_test', 'Run',
           'runs_of', 'Signature', 'StateEvidence', 'velocity_residuals', 'VOCABULARY']

"""The detectors of the discrepancy workflow, one word of the vocabulary each (methods 8.5)."""

from __future__ import annotations

from hydro_sdp.core.diagnosis.detectors.angle import (
    AngleDependentVelocityDetector, AngleLimitsDetector)
from hydro_sdp.core.diagnosis.detectors.base import Detector, feature_signature
from hydro_sdp.core.diagnosis.detectors.delays import (
    DirectionDependentDelayDetector, TimeDelayDetector)
from hydro_sdp.core.diagnosis.detectors.dynamics import (
    BacklashDetector, OscillationDetector, ValveLagDetector)
from hydro_sdp.core.diagnosis.detectors.load import LoadDependenceDetector
from hydro_sdp.core.diagnosis.detectors.map_shape import (
    AsymmetryDetector, DeadZoneDetector, VelocitySaturationDetector)
from hydro_sdp.core.diagnosis.detectors.pump import FlowSharingDetector
from hydro_sdp.core.diagnosis.detectors.stroke_shape import StrokeGeometryDetector
from hydro_sdp.core.errors import ConfigurationError

#: Every detector, in the order the search tries them (ties in gain go to the first).
DETECTORS: tuple[Detector, ...] = (
    DeadZoneDetector(), VelocitySaturationDetector(), AsymmetryDetector(), TimeDelayDetector(),
    DirectionDependentDelayDetector(), AngleLimitsDetector(), ValveLagDetector(),
    BacklashDetector(), AngleDependentVelocityDetector(), StrokeGeometryDetector(),
    FlowSharingDetector(), LoadDependenceDetector(), OscillationDetector(),
)

#: The vocabulary: every word the workflow can name (besides ``none``).
VOCABULARY: tuple[str, ...] = tuple(detector.word for detector in DETECTORS)


def detector(word: str) -> Detector:
    """Return the detector of a vocabulary word."""
    for candidate in DETECTORS:
        if candidate.word == word:
            return candidate
    raise ConfigurationError(f'unknown effect {word!r} (known: {", ".join(VOCABULARY)})')


def vocabulary_table() -> list[str]:
    """Return the vocabulary as Markdown table rows: word, what is missed, how it is added."""
    return ['| word | what the model misses | how it is added |', '|---|---|---|',
            *[f'| `{d.word}` | {d.description} | {d.remedy} |' for d in DETECTORS]]


__all__ = ['DETECTORS', 'Detector', 'detector', 'feature_signature', 'VOCABULARY',
           'vocabulary_table']

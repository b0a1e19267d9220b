"""The non-parametric stage of the SDP method: how a parameter depends on a state (methods 14)."""

from hydro_sdp.core.identification.sdp.analysis import analyse
from hydro_sdp.core.identification.sdp.backfit import Backfit, backfit, Term, TermEstimate
from hydro_sdp.core.identification.sdp.dependence import (
    ParameterSummary, SdpAnalysis, StateDependence, Target)
from hydro_sdp.core.identification.sdp.states import STATES

__all__ = ['Backfit', 'ParameterSummary', 'STATES', 'SdpAnalysis', 'StateDependence', 'Target',
           'Term', 'TermEstimate', 'analyse', 'backfit']

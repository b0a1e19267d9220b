"""The non-parametric stage of the SDP method: how a parameter depends on a state (methods 14)."""

from hydro_sdp.core.identification.state_dependence.analysis import analyse
from hydro_sdp.core.identification.state_dependence.backfit import (
    Backfit, backfit, Term, TermEstimate)
from hydro_sdp.core.identification.state_dependence.dependence import (
    ParameterSummary, SdpAnalysis, StateDependence, Target)
from hydro_sdp.core.identification.state_dependence.states import STATES

__all__ = ['Backfit', 'ParameterSummary', 'STATES', 'SdpAnalysis', 'StateDependence', 'Target',
           'Term', 'TermEstimate', 'analyse', 'backfit']

"""
The non-parametric stage of the SDP method: how a parameter depends on a state.

Young's state-dependent parameter estimation (Young 2000; Young, McKenna and
Bruun 2001; CAPTAIN's ``sdp``), docs/methods.md section 14. A parameter is
estimated along the samples sorted by a candidate state (:mod:`.ordering`) as
a random walk or an integrated random walk (:mod:`.random_walk`), by the
fixed-interval smoother in its banded least-squares form (:mod:`.banded`,
checked against the recursive Kalman filter and smoother of :mod:`.kalman`),
its NVR by maximum likelihood (:mod:`.nvr`); several parameters are
back-fitted (:mod:`.backfit`), each weighed by its held-out share
(:mod:`.shares`) and a bootstrap test that respects autocorrelated residuals
(:mod:`.significance`). :func:`analyse` runs the joint analysis: the SDP-ARX
model of a joint, or what a model misses, against the candidate states
(:mod:`.states`), and returns an :class:`SdpAnalysis` (:mod:`.dependence`).

"""

from hydro_sdp.core.identification.sdp.analysis import analyse
from hydro_sdp.core.identification.sdp.backfit import Backfit, backfit, Term, TermEstimate
from hydro_sdp.core.identification.sdp.dependence import (
    ParameterSummary, SdpAnalysis, StateDependence, Target)
from hydro_sdp.core.identification.sdp.states import STATES

__all__ = ['Backfit', 'ParameterSummary', 'STATES', 'SdpAnalysis', 'StateDependence', 'Target',
           'Term', 'TermEstimate', 'analyse', 'backfit']

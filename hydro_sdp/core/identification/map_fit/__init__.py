"""
Fitting the static map of a joint to experiments (docs/methods.md section 2).

One module per map family (``sdp``: eq. (5); ``pwl``: monotone
piecewise-linear, for valves that do not follow eq. (5); ``poly``: the second
paper's polynomial gain) over the shared residual machinery of :mod:`.data`.

"""

from hydro_sdp.core.identification.map_fit.data import (
    FIT_METHODS, FitData, FitMethod, MapFit, RateFunction)
from hydro_sdp.core.identification.map_fit.poly import fit_poly
from hydro_sdp.core.identification.map_fit.pwl import fit_pwl, initial_pwl, pwl_layout, PwlLayout
from hydro_sdp.core.identification.map_fit.sdp import (
    check_excitation, fit_sdp, initial_sdp, sdp_bounds, sdp_from_rate_vector, SDP_NAMES,
    sdp_rate_function)

__all__ = [
    'FIT_METHODS', 'FitData', 'FitMethod', 'MapFit', 'PwlLayout', 'RateFunction', 'SDP_NAMES',
    'check_excitation', 'fit_poly', 'fit_pwl', 'fit_sdp', 'initial_pwl', 'initial_sdp',
    'pwl_layout', 'sdp_bounds', 'sdp_from_rate_vector', 'sdp_rate_function',
]

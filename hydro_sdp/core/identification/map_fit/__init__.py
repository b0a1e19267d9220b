"""Fitting the static map of a joint to experiments (docs/methods.md section 2)."""

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

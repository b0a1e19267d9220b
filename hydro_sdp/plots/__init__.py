"""Figures in the style of West et al. (2018), drawn with matplotlib's object API."""

from hydro_sdp.plots.control import (
    plot_closed_loop, plot_idz, plot_idz_table, plot_recalibration)
from hydro_sdp.plots.diagnosis import plot_gap, plot_ledger, plot_signature
from hydro_sdp.plots.figures import (
    LIMIT, matplotlib_colormap, MEASURED, MODEL, new_figure, save_figure)
from hydro_sdp.plots.identification import (
    plot_gains, plot_record, plot_step_responses, plot_velocity_map)
from hydro_sdp.plots.sdp import plot_shares, plot_state
from hydro_sdp.plots.units import command_unit_of, UNKNOWN_UNIT

__all__ = ['command_unit_of', 'LIMIT', 'matplotlib_colormap', 'MEASURED', 'MODEL', 'new_figure',
           'plot_closed_loop', 'plot_gains', 'plot_gap', 'plot_idz', 'plot_idz_table',
           'plot_ledger', 'plot_record', 'plot_recalibration', 'plot_shares', 'plot_signature',
           'plot_state', 'plot_step_responses', 'plot_velocity_map', 'save_figure',
           'UNKNOWN_UNIT']

"""Figures of the SDP analysis: the estimate and its +-2 SE band, drawn where the data are."""

from hydro_sdp.core.identification.delay import LevelSpeed
from hydro_sdp.core.identification.state_dependence.dependence import SdpAnalysis, StateDependence
from hydro_sdp.plots.identification import plot_gains
from hydro_sdp.plots.sdp import plot_shares, plot_state
import numpy as np


def entry(state, direction, values, estimate, se, share=0.3, parameter='b'):
    return StateDependence(state, parameter, direction, share, 0.01, 0.005, True,
                           np.asarray(values, float), np.asarray(estimate, float),
                           np.asarray(se, float), float(np.mean(estimate)), 100)


def analysis(states, residual=()):
    return SdpAnalysis('ratio' if residual else 'arx', 1000, 15, 0.01, 0.0, tuple(states),
                       tuple(residual), None, (), {})


def test_a_state_is_drawn_with_its_band_per_direction():
    angle = np.linspace(-40.0, 40.0, 200)
    up = entry('angle', 'positive', angle, 1.0 + 0.1 * np.sin(angle / 10.0), np.full(200, 0.02),
               parameter='ratio')
    down = entry('angle', 'negative', angle, np.ones(200), np.full(200, 0.05), share=0.0,
                 parameter='ratio')
    down = StateDependence(**{**down.__dict__, 'significant': False})
    offset = entry('angle', 'both', angle, np.zeros(200), np.full(200, 0.01),
                   parameter='residual')
    figure = plot_state(analysis([up, down], [offset]), 'angle')
    gain_ax, residual_ax = figure.axes
    labels = [line.get_label() for line in gain_ax.get_lines()]
    assert 'positive: share 30.0 %, significant' in labels
    assert 'negative: share 0.0 %, not significant' in labels
    # The band is the estimate +- 2 SE.
    band = gain_ax.collections[0].get_paths()[0].vertices
    assert np.min(band[:, 1]) == np.min(up.estimate - 0.04)
    assert residual_ax.get_ylabel() == 'increment residual (deg)'
    assert gain_ax.get_ylabel() == 'measured / model increment'


def test_a_few_levels_are_drawn_as_points_with_error_bars_and_the_shares_as_bars():
    levels = entry('command', 'positive', [1.0, 2.0, 3.0], [0.05, 0.1, 0.08], [0.01] * 3)
    result = analysis([levels, entry('angle', 'positive', np.arange(50.0), np.ones(50),
                                     np.full(50, 0.1), share=0.01)])
    figure = plot_state(result, 'command', command_unit='V')
    (ax,) = figure.axes
    assert ax.get_xlabel() == 'delayed command (V)'
    assert ax.containers          # error bars at each level
    shares = plot_shares(result)
    bars = shares.axes[0].patches
    assert len(bars) == 2 and bars[0].get_width() == 30.0


def test_identify_gains_figure_draws_the_measured_curve_beside_the_map(j2):
    speeds = {v: float(j2.rate(np.array([v]))[0]) for v in (-4.0, -2.0, 2.0, 4.0)}
    points = [LevelSpeed(v, speed, 0.5, 100, 0.01 * speed / v) for v, speed in speeds.items()]
    measured = [entry('command', 'positive', [2.0, 3.0, 4.0], [0.2, 0.25, 0.2], [0.01] * 3)]
    figure = plot_gains(points, j2, 0.01, measured=measured)
    labels = [text.get_text() for text in figure.axes[0].get_legend().get_texts()]
    assert 'measured, positive (SDP, +-2 SE)' in labels
    assert any(label.endswith('model') for label in labels)

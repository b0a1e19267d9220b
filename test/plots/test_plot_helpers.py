"""The shared axis helpers of the figures."""

from hydro_sdp.io.model_files import default_model_path, load_model
from hydro_sdp.plots.figures import (
    label_command_axes, LIMIT, mark_dead_zone, new_figure, save_figure)
from matplotlib.colors import to_hex
from PIL import Image
from support.figures import BLANK_PNG, figures_not_drawn


def test_mark_dead_zone_draws_both_edges_and_the_band():
    figure, (ax,) = new_figure(1)
    mark_dead_zone(ax, (-1.25, 2.5))
    edges = [line.get_xdata()[0] for line in ax.get_lines()]
    assert edges == [-1.25, 2.5]
    assert all(line.get_linestyle() == '--' for line in ax.get_lines())
    (band,) = ax.patches
    assert band.get_label() == 'dead-zone' and to_hex(band.get_facecolor()) == LIMIT


def test_label_command_axes_names_the_command_unit():
    model = load_model(default_model_path())
    figure, (ax,) = new_figure(1)
    ax.plot([0.0, 1.0], [0.0, 1.0], label='model')
    label_command_axes(ax, model, 'V', 'angular velocity (deg/s)', 'center left')
    assert ax.get_xlabel() == 'steady command v (V)'
    assert ax.get_ylabel() == 'angular velocity (deg/s)'
    assert [text.get_text() for text in ax.get_legend().get_texts()] == ['model']


def test_figures_not_drawn_are_blank_pngs_and_drawn_ones_are_not(tmp_path):
    figure, (ax,) = new_figure(1)
    ax.plot([0.0, 1.0], [0.0, 1.0])
    with figures_not_drawn():
        save_figure(figure, tmp_path / 'blank.png')
    save_figure(figure, tmp_path / 'drawn.png')
    assert (tmp_path / 'blank.png').read_bytes() == BLANK_PNG
    with Image.open(tmp_path / 'blank.png') as blank, Image.open(tmp_path / 'drawn.png') as drawn:
        assert blank.size == (1, 1)
        assert drawn.size[0] > 100 and drawn.size[1] > 100

"""The bucket-line figure: the tip's sideways deviation drawn magnified, panels per joint."""

from hydro_sdp.core.control.loop_simulation import LoopTrace
from hydro_sdp.plots.bucket_line import plot_bucket_line
import numpy as np


def _trace(joint, t, setpoint, y):
    zeros = np.zeros_like(t)
    return LoopTrace(joint, t, y, y, zeros, zeros, setpoint)


def test_tip_deviation_is_drawn_magnified_during_the_motion_only():
    t = np.linspace(0.0, 4.0, 401)
    line = ((0.0, 0.0), (1.0, -1.0))
    # The tip runs along the line 1 mm to its upper right (normal (1, 1) / sqrt 2).
    along = np.clip(t - 1.0, 0.0, 1.0)
    offset = 0.001
    x = along + offset / np.sqrt(2.0)
    z = -along + offset / np.sqrt(2.0)
    path = np.full_like(t, 1000.0 * offset)
    traces = [_trace('boom', t, 40.0 - 10.0 * along, 40.0 - 10.0 * along + 0.1),
              _trace('dipper', t, -100.0 + 20.0 * along, -100.0 + 20.0 * along)]
    figure = plot_bucket_line(x, z, line, path, traces, (1.0, 2.0), magnify=100.0)
    path_ax, error_ax, boom_ax, dipper_ax = figure.axes
    tip = next(drawn for drawn in path_ax.get_lines()
               if drawn.get_label().startswith('bucket tip'))
    drawn_x, drawn_z = tip.get_data()
    moving = (t >= 1.0) & (t <= 2.0)
    assert len(drawn_x) == moving.sum()
    # 1 mm drawn as 100 mm along the normal, signed: the drawn tip is 0.1 m from the line.
    distance = (drawn_x + drawn_z) / np.sqrt(2.0)
    np.testing.assert_allclose(distance, 0.1, rtol=1e-9)
    assert error_ax.get_ylabel() == 'path error (mm)'
    assert any('max 1.00 mm, RMS 1.00 mm' in text.get_text() for text in error_ax.texts)
    assert boom_ax.get_ylabel() == 'boom angle (deg)'
    assert any('RMS error 0.10 deg' in text.get_text() for text in boom_ax.texts)
    assert dipper_ax.get_ylabel() == 'dipper angle (deg)'
    assert any('RMS error 0.00 deg' in text.get_text() for text in dipper_ax.texts)


def test_the_demanded_line_is_drawn_over_the_tip_and_a_peak_after_the_motion_says_so():
    t = np.linspace(0.0, 4.0, 401)
    line = ((0.0, 0.0), (1.0, -1.0))
    along = np.clip(t - 1.0, 0.0, 1.0)
    # On the line during the motion; 6 mm off at 3 s, while the joints settle.
    path = np.where(np.abs(t - 3.0) < 0.2, 6.0, 0.2)
    traces = [_trace('boom', t, along, along), _trace('dipper', t, along, along)]
    figure = plot_bucket_line(along, -along, line, path, traces, (1.0, 2.0))
    path_ax, error_ax = figure.axes[:2]
    drawn = {artist.get_label(): artist for artist in path_ax.get_lines()}
    demanded = drawn['demanded line']
    tip = next(a for label, a in drawn.items() if label.startswith('bucket tip'))
    assert demanded.get_zorder() > tip.get_zorder() and demanded.get_linestyle() == '--'
    notes = [text for text in error_ax.texts if 'after the motion ended' in text.get_text()]
    assert len(notes) == 1 and notes[0].get_text().startswith('6.0 mm after the motion ended')
    assert notes[0].xy == (float(t[np.argmax(path)]), 6.0)
    # No peak after the motion: nothing to say.
    quiet = plot_bucket_line(along, -along, line, np.full_like(t, 0.2), traces, (1.0, 4.0))
    assert not [text for text in quiet.axes[1].texts if 'after' in text.get_text()]

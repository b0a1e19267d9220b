"""The discrepancy report draws what the diagnosis carries; the demo and the CLI share it."""

from pathlib import Path

from hydro_sdp.core.diagnosis import diagnose, runs_of
from hydro_sdp.core.diagnosis.detectors.base import feature_signature
from hydro_sdp.core.diagnosis.results import Candidate
from hydro_sdp.core.model.effects import ValveLag
from hydro_sdp.core.synthetic.joint_experiments import experiment_record
from hydro_sdp.io.model_files import load_model
from hydro_sdp.plots import plot_signature, save_figure
from hydro_sdp.plots.diagnosis import plot_record_scales
from hydro_sdp.report.diagnosis import write_report
import numpy as np
from PIL import Image


def test_a_report_without_an_effect_has_no_signature_but_its_candidates(tmp_path, j2):
    records = [experiment_record(j2, 'random', seed=seed, duration=20.0) for seed in (1, 2)]
    result = diagnose(records[:1], j2, validation=records[1:], max_iterations=0)
    written = write_report(tmp_path / 'report', result)
    assert written == [str(tmp_path / 'report' / name)
                       for name in ('gap.png', 'ledger.png', 'candidates.png', 'summary.md')]
    summary = (tmp_path / 'report' / 'summary.md').read_text()
    assert '**Named effect: `none`.**' in summary
    assert f'Validation MAE {result.mae_before:.4g} deg before, {result.mae_before:.4g} deg ' \
        'after (0 effects added; judged on given: 1 validation record).' in summary
    assert '![candidates](candidates.png)' in summary
    assert '| - | none | - | - | - | - |' in summary
    assert '![signature]' not in summary
    (tmp_path / 'model.yaml').write_text(summary.split('```yaml\n')[1].split('```')[0])
    assert load_model(tmp_path / 'model.yaml') == j2


def test_the_signature_figure_shows_the_features_of_the_signature(j2):
    record = experiment_record(j2, 'random', seed=3, duration=20.0)
    run, = runs_of([record], 0.5)
    lagged = j2.with_effect(ValveLag(0.1))
    for word, feature in (('valve_lag', 'events'), ('dead_zone', 'command'),
                          ('angle_limits', 'angle'), ('backlash', 'reversals')):
        signature = feature_signature(word, feature, j2, lagged, run)
        ax, = plot_signature(signature).axes
        assert ax.get_xlabel() == signature.label
        before, after = (line.get_ydata() for line in ax.get_lines()[:2])
        if signature.x is None:
            # One second of lags, the mean residual (deg/s) signed by each event.
            assert len(before) == 100
            rows = [s * signature.after[t:t + 100] / 0.01
                    for t, s in zip(signature.triggers, signature.signs)
                    if t + 100 <= signature.after.size]
            assert np.allclose(after, np.mean(rows, axis=0))
            assert rows
        else:
            assert 0 < len(before) <= 30


def test_every_figure_of_a_named_effect_is_drawn_whole(tmp_path, j2):
    # Drawn here for real: the tests of what commands compute write them as blank PNGs
    # (support.figures), the docs examples too.
    lagged = j2.with_effect(ValveLag(0.12))
    records = [experiment_record(lagged, 'random', seed=seed, duration=20.0) for seed in (1, 2)]
    result = diagnose(records[:1], j2, validation=records[1:], max_iterations=1)
    assert result.effect == 'valve_lag' and result.evidence is not None
    pngs = [Path(path) for path in write_report(tmp_path / 'report', result)
            if path.endswith('.png')]
    scales = Candidate('load_dependence', True, parameters={
        'scales_positive': [1.0, 0.8, None], 'errors_positive': [0.02, 0.03, None],
        'scales_negative': [1.1, 1.0, 0.9], 'errors_negative': [0.02, 0.02, 0.04]})
    pngs.append(save_figure(plot_record_scales(scales), tmp_path / 'record_scales.png'))
    assert {png.name for png in pngs} == {'gap.png', 'signature.png', 'evidence.png',
                                          'ledger.png', 'candidates.png', 'record_scales.png'}
    for png in pngs:
        with Image.open(png) as image:
            assert min(image.size) > 300, png.name

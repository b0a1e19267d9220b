"""
calibrate on CSV logs of a joint whose map is a measured table; its controller file runs the joint.

The joint (:mod:`support.table_valve_joint`) is no SDP model: its speed is a
monotone cubic through measured points (nothing below about 36 % duty, a
convex rise to about 30 deg/s by 80 %, flat after), behind a 0.28 s dead time
and a 0.15 s spool lag acting before the map. Logged as a user would, one duty
from stop to stop and back per file, in signed percent and in percent resting
at 50; read as ``hydro-sdp calibrate`` reads CSV logs, identified on 40/60/80/100 %
and validated on 50/70/90 % (the command's pipeline without its report, which
takes longer to draw than the calibration). The controller file it writes is
then run against the joint itself by the loop of
:mod:`support.independent_loop` (none of hydro_sdp's controller classes): every
step of 20-25 deg settles into +-0.5 deg within 8 s, overshoots at most 10 %
and ends its hold without a limit cycle. The table's first design pulses at hold
(the valve jumps across the 36 % dead-zone at every small error): calibrate's
check finds it and fades the compensation in, and on the true joint the first
design pulses several times a second while the file written holds still.

"""

from dataclasses import replace


from hydro_sdp.core.calibration import calibrate, CalibrationSettings
from hydro_sdp.core.control.loop_chatter import MAX_PULSE_RATE
from hydro_sdp.io.controller_files import load_controller, save_controller
from hydro_sdp.io.documents import load_yaml
from hydro_sdp.io.logs.csv_logs import read_csv_log
import pytest
from support.real_valve_joints import cases, cycles, pulse_rate, SETTLE, settles, truth_loop
from support.spurious_words import OWN

pytestmark = [pytest.mark.usefixtures('figures_not_drawn')]


def read_logs(paths, options):
    """Read CSV logs with the command line's options (``--joint arm --time t ...``)."""
    names = dict(zip(options[::2], options[1::2]))
    return [read_csv_log(path, joint=names['--joint'], time=names['--time'],
                         angle=names['--angle'], command=names['--command']).record
            for path in paths]


@pytest.fixture(scope='module', params=['table_signed', 'table_rest50'])
def calibrated(request, tmp_path_factory):
    """Calibrate the joint from its CSV logs; return the case, the result and the file."""
    case = cases()[request.param]
    folder = tmp_path_factory.mktemp(request.param)
    estimation, validation, options = case.write(folder)
    result = calibrate(read_logs(estimation, options), read_logs(validation, options),
                       CalibrationSettings(input_limits=case.input_limits))
    return case, result, save_controller(result.spec, folder / 'controller.yaml')


@pytest.mark.slow
def test_calibrates_check_passes_and_its_file_settles_the_joint(calibrated):
    case, result, path = calibrated
    assert result.check.passed and result.check.cycles == 0, result.warnings
    # The joint has a lag and no linkage, load, other joint nor play: no word it lacks.
    assert set(result.effects) <= OWN, result.effects
    # The map is no SDP curve: the IDZ inverts it as a table, on the model's own dynamics.
    model = result.model
    data = load_yaml(path)
    assert model.kind != 'sdp' and result.forms[-1] == 'table' and 'table' in data['idz']
    lag = model.effect('valve_lag')
    assert data['plant'].get('valve_lag') == (None if lag is None else lag.time_constant)
    assert load_controller(path).delay_samples == model.delay_samples(0.05)
    results = truth_loop(case, path)
    for r in results:
        assert r.settling <= SETTLE, f'the {r.size:+.0f} deg step settles in {r.settling} s'
        assert r.overshoot <= 10.0, f'the {r.size:+.0f} deg step overshoots {r.overshoot:.1f} %'
    assert cycles(results) == 0 and settles(results)


@pytest.mark.slow
def test_the_pulsing_table_fades_in_and_the_true_joint_holds_still(calibrated, tmp_path):
    case, result, path = calibrated
    band, fade = result.trade
    assert not band.passed and band.pulse_rate > 2.0 * MAX_PULSE_RATE and band.fade == 0.0
    assert fade.passed and fade.pulse_rate < 0.5 * MAX_PULSE_RATE and fade.fade > 0.0
    assert result.spec.idz.fade == fade.fade == result.fades[-1]
    # The same design without the fade, and the file written, on the true joint.
    first = save_controller(replace(result.spec, idz=replace(result.spec.idz, fade=0.0)),
                            tmp_path / 'band.yaml')
    before, after = pulse_rate(truth_loop(case, first)), pulse_rate(truth_loop(case, path))
    assert before > 4.0 * MAX_PULSE_RATE and after < 0.2 * MAX_PULSE_RATE, (before, after)

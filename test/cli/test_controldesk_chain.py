"""
An excavator's ControlDesk exports through the whole chain, as a new user would run it.

One run per file: the arm driven at one duty, 40, 70 or 100 %, in both directions from
end stop to end stop, the boom moving on the same pump in some runs, the pump pressure on
a raster of its own. The files are ControlDesk recorder exports in CP949 (Korean
metadata), signals named ``In1``/``Out1`` with their names in the path, an unnamed time
column 0.0099909 s apart on the logger's clock. ``import`` reads them by the names a user
sees, ``identify`` and ``design`` give the model and the controller of the same runs
logged at 0.01 s, and ``calibrate`` takes the files themselves.
"""

import numpy as np
import pytest
from support.cli_runs import run_json
from support.controldesk_files import Trace, write_controldesk
from support.plain_joint import PlainJoint

pytestmark = [pytest.mark.usefixtures('figures_not_drawn'), pytest.mark.slow(6)]

#: The arm (duty in %, a dead-zone the slowest runs come near) and the boom.
ARM = PlainJoint(delay=9, dead_zone=(-28.0, 25.0), slope=(0.9, 1.1), saturation=(30.0, 36.0),
                 stops=(-25.0, 35.0), noise=0.02)
BOOM = PlainJoint(delay=7, dead_zone=(-20.0, 20.0), slope=(0.5, 0.5), saturation=(15.0, 15.0),
                  stops=(-40.0, 40.0))
DUTIES = (40.0, 70.0, 100.0)
#: The logger's clock: a 10 ms raster read 0.09 % fast.
CLOCK = 0.0099909


def full_stroke(duty):
    """Rest at one stop, the duty held to the other stop and a moment against it, rest."""
    start = ARM.stops[0] + 0.5 if duty > 0 else ARM.stops[1] - 0.5
    travel = (ARM.stops[1] - ARM.stops[0]) / abs(ARM.speed(duty))
    commands = np.r_[np.zeros(60), np.full(int((travel + 0.4) / ARM.dt), duty), np.zeros(40)]
    return ARM.run(commands, y0=start, seed=int(abs(duty)) + (duty < 0))


def runs():
    """Each run: the arm record and, every other run, the boom moving on the same pump."""
    out = {}
    for index, duty in enumerate(d * sign for d in DUTIES for sign in (1.0, -1.0)):
        arm = full_stroke(duty)
        boom = BOOM.run_levels(len(arm) * 0.01, magnitude=(30.0, 60.0), seed=index).y \
            if index % 2 else np.zeros(len(arm))
        out[f'arm_{"up" if duty > 0 else "down"}_{abs(duty):03.0f}'] = (arm, boom[:len(arm)])
    return out


def logged(record):
    """Row k of a logger's file holds the command it applied at t_k: v_{k+1} of the record."""
    return np.r_[record.v[1:], record.v[-1]]


def write_exports(folder, period):
    for name, (arm, boom) in runs().items():
        t = np.arange(len(arm)) * period
        pump_t = np.arange(len(arm) // 2) * 2 * period
        write_controldesk(folder / f'{name}.csv', [
            (t, [Trace('In1', 'Model Root/Arm/Arm_ang/In1', 'deg', arm.y),
                 Trace('In1', 'Model Root/Boom/Boom_ang/In1', 'deg', boom),
                 Trace('Out1', 'Model Root/Valves/Arm_duty/Out1', '%', logged(arm))]),
            (pump_t, [Trace('In1', 'Model Root/Pump/Pump_P/In1', 'bar',
                            180.0 + 20.0 * np.sin(pump_t))])])
    return sorted(folder.glob('*.csv'))


def write_plain_csv(folder):
    """Write the same runs as plain CSVs logged at 0.01 s."""
    for name, (arm, _) in runs().items():
        rows = [f'{0.01 * k!r},{float(y)!r},{float(v)!r}'
                for k, (y, v) in enumerate(zip(arm.y, logged(arm)))]
        (folder / f'{name}.csv').write_text('t,Arm_ang,Arm_duty\n' + '\n'.join(rows) + '\n')
    return sorted(folder.glob('*.csv'))


MACHINE = """\
joints:
  arm: {angle: Arm_ang, command: Arm_duty}
  boom: {angle: Boom_ang}
signals:
  pump/pressure: Pump_P
"""


def chain(files, out, *options):
    """import, identify the arm, design its controller at its records' period."""
    imported = run_json('import', *files, '--out', out / 'bags', *options)
    identified = run_json('identify', *imported['bags'], '--joint', 'arm', '--input-limits',
                          -100, 100, '--out', out / 'arm.yaml')
    designed = run_json('design', out / 'arm.yaml', '--sample-period',
                        identified['sample_period'])
    return imported, identified, designed


def test_controldesk_exports_give_the_model_and_controller_of_a_clean_log(tmp_path):
    (tmp_path / 'cd').mkdir()
    (tmp_path / 'plain').mkdir()
    (tmp_path / 'machine.yaml').write_text(MACHINE)
    imported, identified, designed = chain(write_exports(tmp_path / 'cd', CLOCK), tmp_path / 'cd',
                                           '--signals', tmp_path / 'machine.yaml')
    assert imported['joints'] == ['arm', 'boom'] and imported['signals'] == ['/pump/pressure']
    for notes in imported['notes']:     # the Korean metadata, then the layout
        assert len(notes) == 2 and notes[0].startswith('not UTF-8 (byte ')
        assert notes[1] == 'read as a dSPACE ControlDesk export: 2 sections, 4 signals'
    plain = chain(write_plain_csv(tmp_path / 'plain'), tmp_path / 'plain', '--joint', 'arm',
                  '--time', 't', '--angle', 'Arm_ang', '--command', 'Arm_duty')
    _, clean, clean_design = plain
    dt = identified['sample_period']
    assert clean['sample_period'] == 0.01 and dt == pytest.approx(CLOCK, rel=1e-4)
    # The delay in samples (the arm's 9) and the map per sample are the clean log's.
    assert round(identified['delay'] / dt) == round(clean['delay'] / 0.01) == ARM.delay
    assert identified['kind'] == clean['kind']
    np.testing.assert_allclose(np.asarray(identified['saturation_velocity']) * dt,
                               np.asarray(clean['saturation_velocity']) * 0.01, rtol=2e-5)
    # Controlled every 5 samples of each: the same gains and IDZ per control sample.
    assert designed['control_samples'] == clean_design['control_samples'] == 5
    assert designed['control_period'] == pytest.approx(5 * dt, rel=1e-12)
    for key in ('f', 'g', 'kI', 'delay_samples'):
        assert designed[key] == clean_design[key], key
    np.testing.assert_allclose(designed['slopes'], clean_design['slopes'], rtol=2e-5)


def test_calibrate_takes_the_exports_on_a_dds_timers_period(tmp_path):
    # 0.00998 s apart, as a DDS timer stamps them: the control period is 5 of its samples.
    files = write_exports(tmp_path, 0.00998)
    result = run_json('calibrate', *files, '--joint', 'arm', '--angle', 'Arm_ang', '--command',
                      'Arm_duty', '--input-limits', -100, 100, '--out', tmp_path / 'arm')
    assert result['sample_period'] == 0.00998
    assert result['control_samples'] == 5 and result['control_period'] == 0.0499
    assert result['closed_loop']['passed']

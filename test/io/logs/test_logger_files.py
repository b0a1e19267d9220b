"""
Loggers' files: MDF4, MATLAB v5 and v7.3, CSV with the logger's lines above the header.

MDF4 files are written by asammdf, MATLAB v5 by scipy and v7.3 (HDF5) by h5py; identify
on an import equals identify on the same data written as a bag.
"""

from asammdf import MDF, Signal
import h5py
from hydro_sdp.bags import read_bag, read_record, write_bag
from hydro_sdp.cli.main import main
from hydro_sdp.core.identification.identify import identify
from hydro_sdp.core.synthetic.joint_experiments import experiment_record
from hydro_sdp.io.logs import read_machine_log, single_joint_spec
import numpy as np
import pytest
from scipy.io import savemat
from support.cli_runs import json_result

COLUMNS = ['--joint', 'j2', '--angle', 'J2_ang', '--command', 'J2_cmd']


def logged(record):
    """Row k of a logger's file holds the command applied at t_k: v_{k+1} of the record."""
    return np.r_[record.v[1:], 99.0]


def write_mdf(path, groups):
    """Write an MDF4 file: ``groups`` is a list of (time, {name: values})."""
    mdf = MDF(version='4.10')
    for t, channels in groups:
        mdf.append([Signal(np.asarray(values, dtype=np.float64), np.asarray(t, dtype=np.float64),
                           name=name) for name, values in channels.items()])
    mdf.save(str(path), overwrite=True)
    mdf.close()
    return path


def write_mat73(path, variables, struct=None):
    """Write a MATLAB 7.3 file as MATLAB does: HDF5 behind a 512-byte MATLAB header."""
    with h5py.File(path, 'w', userblock_size=512) as handle:
        for group, values in [(handle, variables)] + (
                [(handle.create_group(struct[0]), struct[1])] if struct else []):
            for name, data in values.items():
                # MATLAB stores a column vector N x 1 as a 1 x N dataset (column-major).
                dataset = group.create_dataset(name, data=np.asarray(data, dtype=np.float64)[None])
                dataset.attrs['MATLAB_class'] = np.bytes_('double')
    header = (b'MATLAB 7.3 MAT-file, Platform: GLNXA64, Created on: Mon Jan  5 10:00:00 2026 '
              b'HDF5 schema 1.00 .')
    with open(path, 'r+b') as handle:
        handle.write(header.ljust(116, b' ') + b'\x00' * 8 + b'\x00\x02IM')
    return path


@pytest.fixture(scope='module')
def steps(j2):
    """J2 step experiments (noisy), and identify on the same data written as a bag."""
    record = experiment_record(j2, 'steps', duration=40.0, seed=3)
    return record


@pytest.fixture(scope='module')
def direct(steps, tmp_path_factory):
    bag = write_bag(tmp_path_factory.mktemp('direct') / 'steps', [steps])
    return identify([read_record(bag)])


def _same_model(imported, direct):
    a, b = imported.model.to_mapping(), direct.model.to_mapping()
    assert a.keys() == b.keys()
    for key in a:
        if key in ('dead_zone', 'saturation_velocity', 'curvature'):
            np.testing.assert_allclose(a[key], b[key], rtol=1e-9)
        else:
            assert a[key] == b[key], key


@pytest.mark.parametrize('kind', ['mdf', 'mat5', 'mat73'])
def test_identify_on_an_import_equals_identify_on_the_bag(steps, direct, tmp_path, kind):
    channels = {'J2_ang': steps.y, 'J2_cmd': logged(steps)}
    # A logger's clock since 1970: only differences of time matter.
    t = steps.t + 1.76e9 if kind != 'mdf' else steps.t + 12.5
    if kind == 'mdf':
        # The angle at 100 Hz and the command in a group of its own at the same instants,
        # a pressure at 1 kHz in a third: each channel on its own time base.
        source = write_mdf(tmp_path / 'run.mf4', [
            (t, {'J2_ang': steps.y}), (t, {'J2_cmd': logged(steps)}),
            (np.arange(t[0], t[-1], 0.001),
             {'J2_P': np.zeros(int(round((t[-1] - t[0]) / 0.001)))})])
        options = []
    elif kind == 'mat5':
        source = tmp_path / 'run.mat'
        savemat(source, {'t': t[:, None], 'log': {'J2_ang': steps.y[:, None],
                                                  'J2_cmd': logged(steps)[:, None]}})
        options = ['--time', 't']
        channels = {}
    else:
        source = write_mat73(tmp_path / 'run.mat', {'t': t}, ('log', channels))
        options = ['--time', 't']
    angle, command = ('J2_ang', 'J2_cmd') if kind == 'mdf' else ('log.J2_ang', 'log.J2_cmd')
    code, payload = json_result('import', source, '--out', tmp_path / 'bags', '--joint', 'j2',
                                '--angle', angle, '--command', command, *options)
    assert code == 0
    assert payload['samples'] == [len(steps)] and payload['joints'] == ['j2']
    back = read_record(payload['bags'][0])
    np.testing.assert_array_equal(back.v, steps.v)
    np.testing.assert_allclose(back.y, steps.y, rtol=1e-14, atol=1e-12)
    _same_model(identify([back]), direct)


def test_channels_at_other_rates_hold_their_last_value(tmp_path):
    # Angle at 100 Hz; duty at 50 Hz, 3 ms off the angle's clock; pressure at 1 kHz.
    t = 100.0 + np.arange(300) * 0.01
    duty_t = 100.003 + np.arange(150) * 0.02
    duty = np.arange(150, dtype=float)
    pressure_t = 99.9995 + np.arange(3000) * 0.001
    pressure = np.arange(3000, dtype=float)
    source = write_mdf(tmp_path / 'rates.mf4', [
        (t, {'Arm_ang': np.linspace(0.0, 10.0, 300)}), (duty_t, {'Arm_duty': duty}),
        (pressure_t, {'Arm_P': pressure})])
    (tmp_path / 'machine.yaml').write_text(
        'joints:\n  arm: {angle: Arm_ang, command: Arm_duty}\nsignals:\n  arm/pressure: Arm_P\n')
    code, payload = json_result('import', source, '--out', tmp_path / 'bags', '--signals',
                                tmp_path / 'machine.yaml')
    assert code == 0 and payload['signals'] == ['/arm/pressure']
    record = read_bag(payload['bags'][0]).record('arm', load_topic='/arm/pressure')
    # Independently: the command is the last one logged strictly before each sample (the
    # first one before it arrives); the pressure the last at or before it.
    for k, when in enumerate(t):
        before = [d for d, s in zip(duty, duty_t) if s < when - 1e-9]
        assert record.v[k] == (before[-1] if before else duty[0])
        at = [p for p, s in zip(pressure, pressure_t) if s <= when + 1e-9]
        assert record.load[k] == at[-1]


def test_csv_with_the_loggers_lines_above_the_header(tmp_path):
    text = ('Logger: ACME DL-200 serial 4711\nDate,2026-01-05\nSample rate,100,Hz\n\n'
            'time,angle,command\n0.5,10,1\n0.6,11,2\n0.7,12,3\n')
    (tmp_path / 'log.csv').write_text(text)
    log = read_machine_log(tmp_path / 'log.csv',
                           single_joint_spec('arm', 'angle', 'command', time='time'))
    np.testing.assert_array_equal(log.records[0].y, [10, 11, 12])
    np.testing.assert_array_equal(log.records[0].v, [1, 1, 2])
    # A units row under the names: part of the header block, found or named.
    units = text.replace('time,angle,command\n', 'time,angle,command\ns,deg,%\n')
    (tmp_path / 'units.csv').write_text(units)
    spec = single_joint_spec('arm', 'angle', 'command', time='time')
    for header_row in (None, 5):
        log = read_machine_log(tmp_path / 'units.csv', spec, header_row=header_row)
        np.testing.assert_array_equal(log.records[0].y, [10, 11, 12])


MACHINE = """\
time: t
angle_unit: deg
joints:
  boom: {angle: Boom_ang, command: Boom_up_duty, command_negative: Boom_dn_duty}
  arm:  {angle: Arm_ang,  command: Arm_out_duty}
signals:
  boom/head_pressure: Boom_head_P
"""


def machine_table(n=200):
    t = 1.76e9 + np.arange(n) * 0.01
    rng = np.random.default_rng(1)
    return {'t': t, 'Boom_ang': np.linspace(0, 20, n), 'Boom_up_duty': rng.uniform(0, 50, n),
            'Boom_dn_duty': rng.uniform(0, 50, n), 'Arm_ang': np.linspace(-30, 0, n),
            'Arm_out_duty': rng.uniform(-80, 80, n), 'Boom_head_P': rng.uniform(50, 150, n)}


def test_a_whole_machine_in_one_bag(tmp_path):
    table = machine_table()
    savemat(tmp_path / 'run1.mat', {name: values[:, None] for name, values in table.items()})
    (tmp_path / 'machine.yaml').write_text(MACHINE)
    code, payload = json_result('import', tmp_path / 'run1.mat', '--out', tmp_path / 'bags',
                                '--signals', tmp_path / 'machine.yaml')
    assert code == 0
    assert set(payload) >= {'bags', 'samples', 'joints', 'signals'}
    assert payload['joints'] == ['boom', 'arm'] and payload['signals'] == ['/boom/head_pressure']
    data = read_bag(payload['bags'][0])
    assert data.names == ('boom', 'arm')
    assert set(data.floats) == {'/boom/valve_command', '/arm/valve_command',
                                '/boom/head_pressure'}
    boom = data.record('boom', load_topic='/boom/head_pressure', others=True)
    # Row k's commands act after row k: up minus down of the row before.
    up, down = table['Boom_up_duty'], table['Boom_dn_duty']
    np.testing.assert_allclose(boom.v, np.r_[up[0] - down[0], (up - down)[:-1]])
    np.testing.assert_allclose(boom.others[:, 0], table['Arm_ang'], atol=1e-12)
    np.testing.assert_allclose(boom.load, table['Boom_head_P'])
    arm = data.record('arm')
    np.testing.assert_allclose(arm.v, np.r_[table['Arm_out_duty'][0],
                                            table['Arm_out_duty'][:-1]])


@pytest.mark.parametrize(('yaml_text', 'table_change', 'message'), [
    pytest.param(MACHINE.replace('Arm_ang', 'Arm_angle'), {}, "run.mat: variable 'Arm_angle' "
                 '(joints.arm.angle): no such variable', id='missing_variable'),
    pytest.param(MACHINE, {'t': 'backwards'}, "run.mat: variable 'Boom_ang': time "
                 '1760000000.49 s at sample 51 goes backwards from 1760000000.5 s',
                 id='time_backwards'),
    pytest.param(MACHINE.replace('{angle: Arm_ang,  command', '{command'), {},
                 'machine.yaml: joints.arm: no angle (every joint needs its angle channel)',
                 id='joint_without_angle'),
    pytest.param(MACHINE.replace('signals:', 'signal:'), {},
                 "machine.yaml: unknown key 'signal' (keys: time, angle_unit, joints, signals)",
                 id='unknown_key'),
    pytest.param(MACHINE.replace('command_negative', 'command_neg'), {},
                 "machine.yaml: joints.boom: unknown key 'command_neg'", id='unknown_joint_key'),
    pytest.param(MACHINE.replace('signals:\n  boom/head_pressure: Boom_head_P', 'signals: 5'), {},
                 'machine.yaml: signals: expected a mapping, got int', id='signals_not_a_mapping'),
    pytest.param('time: t\njoints: 5\n', {}, 'machine.yaml: joints: expected a mapping, got int',
                 id='joints_not_a_mapping'),
    pytest.param(MACHINE, {'Arm_ang': 'short'}, "run.mat: variable 'Arm_ang' (joints.arm.angle):"
                 ' 100 samples, the time variable has 200', id='different_length'),
    pytest.param(MACHINE, {'Boom_head_P': 'nan'}, "run.mat: variable 'Boom_head_P': 1 values "
                 'are NaN or infinite (first at sample 7)', id='nan_value'),
])
def test_bad_machine_inputs_name_the_file_the_channel_and_the_reason(
        tmp_path, capsys, yaml_text, table_change, message):
    table = machine_table()
    for name, change in table_change.items():
        if change == 'backwards':
            table[name][51] = table[name][49]
        elif change == 'short':
            table[name] = table[name][:100]
        else:
            table[name][7] = np.nan
    savemat(tmp_path / 'run.mat', {name: values[:, None] for name, values in table.items()})
    (tmp_path / 'machine.yaml').write_text(yaml_text)
    code = main(['import', str(tmp_path / 'run.mat'), '--out', str(tmp_path / 'bags'),
                 '--signals', str(tmp_path / 'machine.yaml')])
    err = capsys.readouterr().err
    assert code == 2 and err.startswith('error: ') and err.count('\n') == 1, err
    assert message in err
    assert not (tmp_path / 'bags').exists()


def test_bad_mdf_and_mat_inputs(tmp_path, capsys):
    t = np.arange(100) * 0.01
    write_mdf(tmp_path / 'twice.mf4', [(t, {'A': t}), (t, {'A': t, 'B': t})])
    write_mdf(tmp_path / 'backwards.mf4', [(np.r_[t[:50], t[49:99]], {'A': t, 'B': t})])
    (tmp_path / 'fake.mf4').write_text('not an MDF file\n')
    savemat(tmp_path / 'matrix.mat', {'t': t[:, None], 'A': np.ones((100, 2)), 'B': t[:, None]})
    cases = [
        ('twice.mf4', [], "channel 'A' (--angle): in several channel groups (0, 1)"),
        ('backwards.mf4', [], "channel 'A': time 0.49 s at sample 50 repeats 0.49 s"),
        ('fake.mf4', [], 'fake.mf4: not an MDF file'),
        ('matrix.mat', ['--time', 't'], "variable 'A' (--angle): a 100x2 matrix, not a vector"),
        ('matrix.mat', [], 'a MATLAB file needs its time variable (--time)'),
    ]
    for name, options, message in cases:
        code = main(['import', str(tmp_path / name), '--out', str(tmp_path / 'bags'), '--joint',
                     'arm', '--angle', 'A', '--command', 'B', *options])
        err = capsys.readouterr().err
        assert code == 2 and err.count('\n') == 1 and message in err, (name, err)
    code = main(['import', str(tmp_path / 'twice.mf4'), '--out', str(tmp_path / 'bags'),
                 '--angle', 'A'])
    assert code == 2
    assert 'give --signals FILE, or --joint, --command for one joint' in capsys.readouterr().err

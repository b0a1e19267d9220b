"""``hydro-sdp import``: CSV logs to bags, the timing rule, and refused CSVs."""

import json

from hydro_sdp.bags import raw_messages, read_record, write_bag
from hydro_sdp.bags.cdr import decode_float64
from hydro_sdp.cli.main import main
from hydro_sdp.core.errors import DataError
from hydro_sdp.core.synthetic.joint_experiments import experiment_record
from hydro_sdp.io.logs import parse_csv_log, record_from_log
import numpy as np
import pytest

COLUMNS = ['--joint', 'j2', '--time', 'time', '--angle', 'angle', '--command', 'command']
# Keys of `identify --json` that hold identified numbers.
IDENTIFIED = ('delay', 'dead_zone', 'saturation_velocity', 'curvature', 'alpha', 'beta', 'mae')


def run(capsys, *argv):
    code = main([str(a) for a in argv])
    captured = capsys.readouterr()
    return code, captured.out, captured.err


def _cell(value):
    return repr(float(value))   # shortest text that reads back as the same double


def _logged(record):
    """Row k of a logger's file holds the command it applied at t_k: v_{k+1} of the record."""
    # The last row's command acts after the log ends; 99 proves it is not used.
    return np.r_[record.v[1:], 99.0]


def write_csv(path, record, *, offset=0.0, unit='deg', split=False, delimiter=','):
    """Write ``record`` the way a logger would: one row per sample."""
    angle = record.y if unit == 'deg' else np.radians(record.y)
    command = _logged(record)
    header = ['time', 'angle', 'command']
    columns = [record.t + offset, angle]
    if split:
        header += ['command_down']
        columns += [np.maximum(command, 0.0), np.maximum(-command, 0.0)]
    else:
        columns += [command]
    lines = [delimiter.join(header)]
    lines += [delimiter.join(_cell(x) for x in row) for row in zip(*columns)]
    path.write_text('\n'.join(lines) + '\n')
    return path


@pytest.fixture(scope='module')
def steps(j2):
    """Simulate J2 step experiments as `simulate` does (noisy, t from one period)."""
    record = experiment_record(j2, 'steps', duration=60.0, seed=1)
    assert record.v[0] == record.v[1]   # at rest before the log began, as the reader assumes
    return record


def _identified(capsys, bag):
    code, out, err = run(capsys, 'identify', bag, '--json')
    assert code == 0, err
    payload = json.loads(out)
    return {key: payload[key] for key in IDENTIFIED}, payload['kind']


@pytest.mark.parametrize('offset', [0.0, 1234.5])
def test_round_trip_identifies_what_the_bag_written_directly_identifies(
        tmp_path, capsys, steps, offset):
    write_bag(tmp_path / 'direct', [steps])
    write_csv(tmp_path / 'run.csv', steps, offset=offset)
    code, out, err = run(capsys, 'import', tmp_path / 'run.csv', '--out', tmp_path / 'bags',
                         *COLUMNS, '--json')
    assert code == 0, err
    assert json.loads(out)['bags'] == [str(tmp_path / 'bags' / 'run')]
    direct, imported = read_record(tmp_path / 'direct'), read_record(tmp_path / 'bags' / 'run')
    # The same samples, stamps and commands in force, to the bit.
    np.testing.assert_array_equal(imported.t, direct.t)
    np.testing.assert_array_equal(imported.v, direct.v)
    np.testing.assert_array_equal(imported.y, direct.y)
    want, kind = _identified(capsys, tmp_path / 'direct')
    got, imported_kind = _identified(capsys, tmp_path / 'bags' / 'run')
    assert kind == imported_kind == 'sdp'
    for key in IDENTIFIED:
        np.testing.assert_allclose(got[key], want[key], rtol=1e-9, atol=1e-12, err_msg=key)
    np.testing.assert_allclose(want['alpha'], (-0.2951, 1.3560, -1.3298, 0.3887, 1.7710, 1.3124),
                               rtol=0.01)


def test_row_command_is_in_force_after_the_row_and_stamped_at_it(tmp_path, capsys):
    # Irregular steps (0.1, 0.1, 0.15 s) on a clock starting at 0.5 s.
    (tmp_path / 'log.csv').write_text(
        'time,angle,command\n0.5,10,1\n0.6,11,2\n0.7,12,3\n0.85,13,4\n')
    code, out, err = run(capsys, 'import', tmp_path / 'log.csv', '--out', tmp_path, *COLUMNS,
                         '--json')
    assert code == 0, err
    payload = json.loads(out)
    assert payload['time_shift'] == [pytest.approx(-0.4)]
    record = read_record(tmp_path / 'log')
    np.testing.assert_allclose(record.t, [0.1, 0.2, 0.3, 0.45], atol=1e-12)
    np.testing.assert_array_equal(record.v, [1, 1, 2, 3])   # v_{k+1} = command of row k
    np.testing.assert_allclose(record.y, [10, 11, 12, 13], atol=1e-12)
    messages = raw_messages(tmp_path / 'log')
    commands = [(stamp, decode_float64([raw])[0]) for topic, _, stamp, raw in messages
                if topic == '/j2/valve_command']
    states = [stamp for topic, _, stamp, _ in messages if topic == '/joint_states']
    # Row k's command is stamped at row k's own time; the one assumed before the log a
    # period earlier. The last row's command acts after the last angle and is not written.
    assert commands == [(0, 1.0), (100_000_000, 1.0), (200_000_000, 2.0), (300_000_000, 3.0)]
    assert states == [100_000_000, 200_000_000, 300_000_000, 450_000_000]


def test_degrees_and_radians(tmp_path, capsys, steps):
    write_csv(tmp_path / 'deg.csv', steps)
    write_csv(tmp_path / 'rad.csv', steps, unit='rad')
    assert run(capsys, 'import', tmp_path / 'deg.csv', tmp_path / 'rad.csv', '--out',
               tmp_path / 'a', *COLUMNS)[0] == 0
    assert run(capsys, 'import', tmp_path / 'rad.csv', '--out', tmp_path / 'b', *COLUMNS,
               '--angle-unit', 'rad')[0] == 0
    # Bags hold radians, so degrees come back to the last bit or two.
    np.testing.assert_allclose(read_record(tmp_path / 'a' / 'deg').y, steps.y, rtol=1e-14)
    # Radians read as degrees (the default) stay the numbers of the file...
    np.testing.assert_allclose(read_record(tmp_path / 'a' / 'rad').y, np.radians(steps.y),
                               rtol=1e-12)
    # ... and with --angle-unit rad they become the joint's degrees again.
    np.testing.assert_allclose(read_record(tmp_path / 'b' / 'rad').y, steps.y, rtol=1e-12,
                               atol=1e-12)


def test_command_negative_is_subtracted(tmp_path, capsys, steps):
    write_csv(tmp_path / 'two_valves.csv', steps, split=True)
    assert run(capsys, 'import', tmp_path / 'two_valves.csv', '--out', tmp_path, *COLUMNS,
               '--command-negative', 'command_down')[0] == 0
    record = read_record(tmp_path / 'two_valves')
    np.testing.assert_array_equal(record.v, steps.v)
    assert record.v.min() < 0.0 < record.v.max()
    # Both valves open at once: the difference is what drives the joint.
    log = parse_csv_log('t,y,up,down\n1,0,3,1\n2,0,0,4\n3,0,5,0\n', joint='arm', time='t',
                        angle='y', command='up', command_negative='down')
    np.testing.assert_array_equal(log.record.v, [2, 2, -4])


def test_headerless_file_by_index_with_other_delimiters(tmp_path, capsys):
    rows = [(0.01, 1.5, 0.0), (0.02, 1.5, 2.0), (0.03, 1.75, 2.0)]
    for name, delimiter, option in (('semi', ';', ';'), ('tabs', '\t', 'tab')):
        (tmp_path / f'{name}.csv').write_text(
            '\n'.join(delimiter.join(str(x) for x in row) for row in rows) + '\n\n')
        code, _, err = run(capsys, 'import', tmp_path / f'{name}.csv', '--out', tmp_path / 'out',
                           '--joint', 'boom', '--time', '0', '--angle', '1', '--command', '2',
                           '--delimiter', option)
        assert code == 0, err
        record = read_record(tmp_path / 'out' / name)
        np.testing.assert_allclose(record.t, [0.01, 0.02, 0.03])
        np.testing.assert_array_equal(record.v, [0.0, 0.0, 2.0])
        np.testing.assert_allclose(record.y, [1.5, 1.5, 1.75], rtol=1e-15)
        assert record.joint == 'boom'
    # A spreadsheet's byte-order mark and spaces around cells are not part of the names.
    (tmp_path / 'bom.csv').write_bytes('\ufefftime , angle, command\n1, 2, 3\n2, 3, 4\n'
                                       .encode('utf-8'))
    assert run(capsys, 'import', tmp_path / 'bom.csv', '--out', tmp_path / 'out',
               *COLUMNS)[0] == 0
    np.testing.assert_allclose(read_record(tmp_path / 'out' / 'bom').y, [2, 3], rtol=1e-15)


def test_json_keys_and_human_output(tmp_path, capsys):
    for name, start in (('first', 0.0), ('second', 100.0)):
        (tmp_path / f'{name}.csv').write_text(
            'time,angle,command\n' + ''.join(f'{start + k * 0.01},{k},0\n' for k in range(5)))
    code, out, err = run(capsys, 'import', tmp_path / 'first.csv', tmp_path / 'second.csv',
                         '--out', tmp_path / 'bags', *COLUMNS, '--storage', 'mcap', '--json')
    assert code == 0, err
    payload = json.loads(out)
    assert set(payload) == {'bags', 'samples', 'sources', 'joint', 'joints', 'signals',
                            'time_shift', 'notes'}
    assert payload['notes'] == [[], []]     # plain UTF-8 tables: nothing to say
    assert payload['bags'] == [str(tmp_path / 'bags' / 'first'), str(tmp_path / 'bags' / 'second')]
    assert payload['samples'] == [5, 5]
    assert payload['sources'] == [str(tmp_path / 'first.csv'), str(tmp_path / 'second.csv')]
    assert payload['joint'] == 'j2'
    np.testing.assert_allclose(payload['time_shift'], [0.01, -99.99])
    assert list((tmp_path / 'bags' / 'first').glob('*.mcap'))
    code, out, _ = run(capsys, 'import', tmp_path / 'first.csv', '--out', tmp_path / 'bags',
                       *COLUMNS)
    assert code == 0
    assert out.startswith(f'wrote {tmp_path / "bags" / "first"} (sqlite3): 5 samples of joint '
                          f'j2 from {tmp_path / "first.csv"}')


GOOD = 'time,angle,command\n0.1,1,0\n0.2,1,0\n'


@pytest.mark.parametrize(('text', 'columns', 'message'), [
    pytest.param(GOOD, ['--command', 'cmd'],
                 "row 1: no column 'cmd' (--command); columns: time, angle, command",
                 id='missing_column'),
    pytest.param('0.1,1,0\n0.2,1,0\n', ['--time', '0', '--angle', '3'],
                 'no column 3 (--angle): the file has 3 columns, 0 to 2', id='index_too_large'),
    pytest.param('\ntime,time,command\n0.1,1,0\n0.2,1,0\n', [],
                 "row 2: 2 columns are named 'time' (--time); choose one by 0-based index",
                 id='column_named_twice'),
    pytest.param('0.1,1,0\n0.2,1,0\n', [],
                 "no column 'time' (--time): the file has no header row, choose columns by "
                 '0-based index', id='name_without_header'),
    pytest.param('time,angle,command\n0.1,1,0\n0.2,1\n', [],
                 "row 3, column 'command': empty (the row has 2 cells)", id='missing_cell'),
    pytest.param('time,angle,command\n0.1,1,0\n0.2,1.0.3,0\n', [],
                 "row 3, column 'angle': '1.0.3' is not a number", id='non_numeric_cell'),
    pytest.param('time,angle,command\n0.1,1,0\n0.2,nan,0\n0.3,NaN,0\n', [],
                 "row 3, column 'angle': 'nan' is not a finite number (2 such cells in the "
                 'column)', id='nan'),
    pytest.param('time,angle,command\n0.1,1,0\n0.2,1,inf\n', [],
                 "row 3, column 'command': 'inf' is not a finite number", id='infinite'),
    pytest.param('time,angle,command\n0.1,1,0\n0.2,1,0\n0.15,1,0\n', [],
                 "row 4, column 'time': time 0.15 s goes backwards from 0.2 s on row 3",
                 id='time_backwards'),
    pytest.param('time,angle,command\n0.1,1,0\n0.2,1,0\n\n0.2,1,0\n', [],
                 "row 5, column 'time': time 0.2 s repeats 0.2 s on row 3", id='time_repeated'),
    pytest.param('time,angle,command\n0.1,1,0\n', [],
                 '1 data row; a log needs at least 2', id='one_row'),
    pytest.param('', [], 'file is empty', id='empty_file'),
    pytest.param('\n  \n', [], 'file is empty', id='blank_file'),
])
def test_bad_csv_is_refused_naming_row_and_column(tmp_path, capsys, text, columns, message):
    (tmp_path / 'bad.csv').write_text(text)
    options = dict(zip(COLUMNS[::2], COLUMNS[1::2]))
    options.update(zip(columns[::2], columns[1::2]))
    argv = [item for option in options.items() for item in option]
    code, out, err = run(capsys, 'import', tmp_path / 'bad.csv', '--out', tmp_path / 'bags',
                         *argv)
    assert code == 2 and out == ''
    assert err == f'error: {tmp_path / "bad.csv"}: {message}\n'
    assert not (tmp_path / 'bags').exists()


def test_every_file_is_checked_before_any_bag_is_written(tmp_path, capsys):
    (tmp_path / 'good.csv').write_text(GOOD)
    (tmp_path / 'bad.csv').write_text(GOOD + '0.3,1,x\n')
    code, _, err = run(capsys, 'import', tmp_path / 'good.csv', tmp_path / 'bad.csv',
                       '--out', tmp_path / 'bags', *COLUMNS)
    assert code == 2
    assert err == f"error: {tmp_path / 'bad.csv'}: row 4, column 'command': 'x' is not a number\n"
    assert not (tmp_path / 'bags').exists()


def test_unreadable_files_and_clashing_names(tmp_path, capsys):
    code, _, err = run(capsys, 'import', tmp_path / 'absent.csv', '--out', tmp_path, *COLUMNS)
    assert code == 2 and err == f'error: {tmp_path / "absent.csv"}: no such file\n'
    # A byte that is not UTF-8 never blocks the table; named as UTF-8, the file is refused.
    (tmp_path / 'latin1.csv').write_bytes(b'time,angle\xb0,command\n1,2,3\n2,3,4\n')
    code, _, err = run(capsys, 'import', tmp_path / 'latin1.csv', '--out', tmp_path, *COLUMNS,
                       '--angle', 'angle\u00b0')
    assert code == 0, err
    code, _, err = run(capsys, 'import', tmp_path / 'latin1.csv', '--out', tmp_path, *COLUMNS,
                       '--encoding', 'utf-8')
    assert code == 2 and err.endswith('latin1.csv: not utf-8 text (byte 10, row 1)\n')
    for folder in ('a', 'b'):
        (tmp_path / folder).mkdir()
        (tmp_path / folder / 'run.csv').write_text(GOOD)
    code, _, err = run(capsys, 'import', tmp_path / 'a' / 'run.csv', tmp_path / 'b' / 'run.csv',
                       '--out', tmp_path / 'bags', *COLUMNS)
    assert code == 2 and 'would both be written to' in err and 'rename one' in err
    assert not (tmp_path / 'bags').exists()
    code, _, err = run(capsys, 'import', tmp_path / 'a' / 'run.csv', '--out', tmp_path / 'bags',
                       *COLUMNS, '--delimiter', ';;')
    assert code == 2 and "delimiter must be one character (or tab, space), got ';;'" in err


def test_existing_bag_is_replaced_whole_or_kept(tmp_path, capsys):
    argv = ['import', tmp_path / 'run.csv', '--out', tmp_path / 'bags', *COLUMNS]
    (tmp_path / 'run.csv').write_text(GOOD)
    assert run(capsys, *argv)[0] == 0
    before = read_record(tmp_path / 'bags' / 'run')
    (tmp_path / 'run.csv').write_text(GOOD + '0.3,x,0\n')
    assert run(capsys, *argv)[0] == 2
    np.testing.assert_array_equal(read_record(tmp_path / 'bags' / 'run').y, before.y)
    (tmp_path / 'run.csv').write_text(GOOD + '0.3,5,0\n')
    assert run(capsys, *argv)[0] == 0
    np.testing.assert_array_equal(read_record(tmp_path / 'bags' / 'run').y, [1, 1, 5])


def test_record_from_log_is_the_timing_rule():
    log = record_from_log(np.array([-2.0, -1.5, -1.0]), np.zeros(3), np.array([4.0, 5.0, 6.0]),
                          joint='arm')
    np.testing.assert_array_equal(log.record.t, [0.5, 1.0, 1.5])
    np.testing.assert_array_equal(log.record.v, [4.0, 4.0, 5.0])
    assert log.time_shift == 2.5
    with pytest.raises(DataError, match='1 rows; a log needs at least 2'):
        record_from_log(np.array([1.0]), np.zeros(1), np.zeros(1), joint='arm')


def test_help_teaches_the_timing_with_an_example(capsys):
    with pytest.raises(SystemExit) as exit_info:
        main(['import', '--help'])
    assert exit_info.value.code == 0
    out = capsys.readouterr().out
    assert 'examples:\n  hydro-sdp import run1.csv run2.csv --out bags --joint arm' in out
    assert 'the angle of the next row is\n  the first that can show it' in out
    assert 'the first sample lands one sample period after\n  t = 0' in out
    assert 'hydro-sdp import day1/*.mf4 --out bags --signals machine.yaml' in out
    for option in ('--angle-unit {deg,rad}', '--command-negative COL', '--delimiter D'):
        assert option in out

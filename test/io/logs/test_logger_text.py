"""
Loggers' text files as they come: encodings, delimiters, header blocks, ControlDesk exports.

Every file is written here, byte for byte, as the logger would: metadata in a Korean code
page around ASCII numbers, UTF-16 with a byte-order mark, semicolons with decimal commas,
quoted cells, trailing delimiters, CRLF, a units row between the names and the numbers,
and dSPACE ControlDesk's layout of keyed rows in sections.
"""

from hydro_sdp.cli.main import main
from hydro_sdp.core.errors import ConfigurationError, DataError
from hydro_sdp.io.logs import read_machine_log, single_joint_spec
from hydro_sdp.io.logs.controldesk import signal_name
from hydro_sdp.io.logs.text_rows import decode_log, sniff_delimiter
import numpy as np
import pytest
from support.controldesk_files import Trace, write_controldesk

KOREAN = '2024년 5월 3일 오후 2:11:12'
N = 40
T = np.arange(N) * 0.0099909                 # a 10 ms raster on the logger's clock
ARM = np.linspace(-20.0, 15.0, N)
BOOM = np.linspace(5.0, -5.0, N)
DUTY = np.r_[np.zeros(10), np.full(N - 10, 60.0)]
T_PUMP = np.arange(2 * N) * 0.005            # a second raster: 5 ms
PUMP = 100.0 + np.arange(2 * N)


def sections():
    """Return an arm and a boom read at Simulink inports, a duty at an outport, a pump at 5 ms."""
    return [(T, [Trace('In1', 'Model Root/Arm/Arm_ang/In1', 'deg', ARM.copy()),
                 Trace('In1', 'Model Root/Boom/Boom_ang', 'deg', BOOM.copy()),
                 Trace('Out1', 'Model Root/Valves/Arm_duty/Out1', '%', DUTY.copy())]),
            (T_PUMP, [Trace('In1', 'Model Root/Pump/Pump_P/In1', 'bar', PUMP.copy())])]


def arm(path, angle='Arm_ang', command='Arm_duty', time=None, **options):
    spec = single_joint_spec('arm', angle, command, time=time)
    return read_machine_log(path, spec, **options)


# --- encodings ---------------------------------------------------------------------------

@pytest.mark.parametrize(('encoding', 'codec'), [
    ('utf-8-sig', 'utf-8-sig'), ('utf-16', 'utf-16'), ('utf-16-be', 'utf-16-be'),
    ('utf-16-le', 'utf-16-le'), ('utf-32', 'utf-32'), ('utf-8', 'utf-8')])
def test_byte_order_marks_and_utf16_without_one_are_read(encoding, codec):
    text = f'date,{KOREAN}\nt,angle\n0.01,1.5\n'
    if encoding == 'utf-16-be':
        data = b'\xfe\xff' + text.encode(encoding)
        codec = 'utf-16'
    else:
        data = text.encode(encoding)
    read = decode_log(data, 'log.csv')
    assert read.text == text and read.encoding == codec and read.note == ''


def test_a_code_page_never_blocks_the_numbers_and_encoding_reads_its_text():
    data = f'date,{KOREAN}\nt,angle\n0.01,1.5\n'.encode('cp949')
    read = decode_log(data, 'log.csv')
    # Latin-1 maps each byte to one character: the ASCII rows come out as written.
    assert read.encoding == 'latin-1' and read.text.endswith('\nt,angle\n0.01,1.5\n')
    assert read.note.startswith('not UTF-8 (byte 9, row 1): read one byte per character')
    assert KOREAN in decode_log(data, 'log.csv', 'cp949').text
    with pytest.raises(DataError, match=r'^log.csv: not utf-8 text \(byte 9, row 1\)$'):
        decode_log(data, 'log.csv', 'utf-8')
    with pytest.raises(ConfigurationError, match="unknown encoding 'korean-ish'"):
        decode_log(data, 'log.csv', 'korean-ish')


# --- delimiters, decimal commas, header blocks ------------------------------------------

@pytest.mark.parametrize(('delimiter', 'decimal'), [(',', '.'), (';', ','), ('\t', ','),
                                                    (';', '.'), ('\t', '.')])
def test_the_delimiter_is_found_and_a_comma_is_a_decimal_point_beside_it(
        tmp_path, delimiter, decimal):
    rows = [['Logger DL-7', ''], ['t', 'angle', 'command'], ['s', 'deg', '%'],
            ['"Zeit"', '"Winkel Arm"', '"Tastgrad"']]
    rows += [[f'{k * 0.01:.2f}', f'{1.5 + k:.3f}', f'{10 * k}'] for k in range(4)]
    text = '\r\n'.join(delimiter.join(cell.replace('.', decimal) for cell in row)
                       for row in rows) + '\r\n'
    assert sniff_delimiter(text) == delimiter
    (tmp_path / 'log.csv').write_bytes(text.encode('cp1252'))
    for angle in ('angle', 'Winkel Arm', '1'):        # a name, a description, an index
        log = arm(tmp_path / 'log.csv', angle=angle, command='command', time='t')
        np.testing.assert_allclose(log.records[0].y, [1.5, 2.5, 3.5, 4.5])
        np.testing.assert_array_equal(log.records[0].v, [0, 0, 10, 20])
        np.testing.assert_allclose(np.diff(log.records[0].t), 0.01)


def test_a_header_block_names_its_columns_and_says_which_row_names_them(tmp_path):
    text = ('run 7, 2024-05-03\n\ntime,angle,command,angle\nTime,Arm angle,Duty,Arm angle 2\n'
            's,deg,%,deg\n0.01,1,0,2\n0.02,2,5,3\n0.03,3,5,4\n')
    (tmp_path / 'log.csv').write_text(text)
    log = arm(tmp_path / 'log.csv', angle='Arm angle', command='Duty', time='Time')
    np.testing.assert_array_equal(log.records[0].y, [1, 2, 3])
    # The names row is named; the rows between it and the numbers are its block.
    log = arm(tmp_path / 'log.csv', angle='Arm angle 2', command='command', time='time',
              header_row=3)
    np.testing.assert_array_equal(log.records[0].y, [2, 3, 4])
    with pytest.raises(DataError, match="row 3: 2 columns are named 'angle'"):
        arm(tmp_path / 'log.csv', angle='angle', command='command', time='time')
    with pytest.raises(DataError, match="row 5: 2 columns are named 'deg'"):
        arm(tmp_path / 'log.csv', angle='deg', command='command', time='time')
    with pytest.raises(DataError, match="row 3: no column 'Winkel' .*; columns: time, angle, "
                                        'command, angle'):
        arm(tmp_path / 'log.csv', angle='Winkel', command='command', time='time')


# --- ControlDesk exports -----------------------------------------------------------------

@pytest.mark.parametrize(('trace', 'path', 'name'), [
    ('In1', 'Model Root/Arm/Arm_ang/In1', 'Arm_ang'),
    ('In1', 'Model Root/Arm/Arm_ang', 'Arm_ang'),
    ('Out2', 'Platform()://Model Root/Valves/Arm_duty/Out2', 'Arm_duty'),
    ('Inport', 'Model Root/Arm_ang/In1/Inport', 'Arm_ang'),
    ('Arm_ang', 'Model Root/Arm/Angle sensor', 'Arm_ang'),
    ('In1', '', 'In1'),
    ('', 'Model Root/Pump/Pump_P', 'Pump_P'),
])
def test_a_signal_is_named_by_its_trace_or_the_last_element_of_its_path(trace, path, name):
    assert signal_name(trace, path) == name


@pytest.mark.parametrize('layout', [
    {},
    {'encoding': 'utf-16'},
    {'delimiter': ';', 'decimal': ','},
    {'delimiter': '\t', 'decimal': ',', 'quote': True},
    {'quote': True, 'trailing': True},
], ids=['cp949', 'utf16_bom', 'semicolon_decimal_comma', 'tab_quoted', 'quoted_trailing'])
def test_a_controldesk_export_reads_by_the_names_a_user_sees(tmp_path, layout):
    source = write_controldesk(tmp_path / 'run.csv', sections(), **layout)
    spec = single_joint_spec('arm', 'Arm_ang', 'Arm_duty')
    log = read_machine_log(source, spec)              # no --time: the section's own
    record = log.records[0]
    np.testing.assert_array_equal(record.y, ARM)
    np.testing.assert_array_equal(record.v, np.r_[DUTY[0], DUTY[:-1]])
    np.testing.assert_allclose(np.diff(record.t), 0.0099909, rtol=1e-9)
    assert log.notes[-1] == 'read as a dSPACE ControlDesk export: 2 sections, 4 signals'
    assert record.sample_period == pytest.approx(0.0099909, rel=1e-4)
    # The same signal by its whole path, the time named, the columns by index.
    by_path = arm(source, angle='Model Root/Arm/Arm_ang/In1', time='time').records[0]
    by_index = arm(source, angle='2', command='4', time='1').records[0]
    for other in (by_path, by_index):
        np.testing.assert_array_equal(other.y, record.y)
        np.testing.assert_array_equal(other.v, record.v)


def test_a_whole_machine_from_a_controldesk_export_each_section_on_its_own_time(tmp_path):
    source = write_controldesk(tmp_path / 'run.csv', sections())
    (tmp_path / 'machine.yaml').write_text(
        'joints:\n  arm: {angle: Arm_ang, command: Arm_duty}\n  boom: {angle: Boom_ang}\n'
        'signals:\n  pump/pressure: Pump_P\n')
    code = main(['import', str(source), '--out', str(tmp_path / 'bags'), '--signals',
                 str(tmp_path / 'machine.yaml')])
    assert code == 0
    from hydro_sdp.bags import read_bag

    data = read_bag(tmp_path / 'bags' / 'run')
    boom = data.record('boom', load_topic='/pump/pressure', others=True)
    np.testing.assert_allclose(np.degrees(np.radians(BOOM)), boom.y, atol=1e-12)
    # The pump at 5 ms: the value logged at or before each 10 ms sample, on its own clock.
    expected = [PUMP[np.flatnonzero(T_PUMP <= t + 1e-12)[-1]] for t in T]
    np.testing.assert_array_equal(boom.load, expected)


@pytest.mark.parametrize(('angle', 'options', 'message'), [
    pytest.param('In1', {}, "3 columns answer to 'In1' (--angle): Model Root/Arm/Arm_ang/In1 "
                 '(section 1, column 2), Model Root/Boom/Boom_ang (section 1, column 3), '
                 'Model Root/Pump/Pump_P/In1 (section 2, column 2); name one by its path',
                 id='port_name_of_several'),
    pytest.param('Arm_angle', {}, "no signal 'Arm_angle' (--angle); signals: Arm_ang, "
                 'Boom_ang, Arm_duty, Pump_P; not UTF-8 (byte ', id='unknown_signal'),
    pytest.param('0', {'time': '1'}, 'column 0 (--angle) holds the row keys of a ControlDesk '
                 'export; its time is column 1', id='key_column'),
    pytest.param('Pump_P', {'time': 'Boom_ang'}, "signal 'Pump_P' (--angle) is in section 2, "
                 'the time named in section 1', id='time_of_another_section'),
    pytest.param('Arm_ang', {'header_row': 5}, 'a ControlDesk export names its columns in its '
                 'trace_names and path rows; leave out --header-row', id='header_row'),
])
def test_bad_controldesk_requests_are_refused_in_one_line(tmp_path, angle, options, message):
    source = write_controldesk(tmp_path / 'run.csv', sections())
    with pytest.raises((DataError, ConfigurationError)) as error:
        arm(source, angle=angle, **options)
    assert message in str(error.value) and '\n' not in str(error.value)


def test_bad_controldesk_cells_name_their_row_and_signal(tmp_path, capsys):
    traces = sections()
    traces[0][1][0].values[3] = np.nan
    source = write_controldesk(tmp_path / 'nan.csv', traces)
    code = main(['import', str(source), '--out', str(tmp_path / 'bags'), '--joint', 'arm',
                 '--angle', 'Arm_ang', '--command', 'Arm_duty'])
    # Three metadata rows and a blank, six keyed rows: the fourth sample is on row 14.
    assert code == 2
    assert capsys.readouterr().err == (f"error: {source}: row 14, signal 'Arm_ang' of section 1: "
                                       "'nan' is not a finite number\n")
    clean = write_controldesk(tmp_path / 'clean.csv', sections()).read_bytes()
    (tmp_path / 'repeat.csv').write_bytes(clean.replace(b'\r\n,0.0299727,', b'\r\n,0.0199818,'))
    with pytest.raises(DataError, match=r'row 14, the time column of section 1: time '
                                        r'0.0199818 s repeats 0.0199818 s on row 13'):
        arm(tmp_path / 'repeat.csv')

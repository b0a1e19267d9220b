"""Reading text files: every failure is one typed line naming the file."""

from hydro_sdp.core.errors import DataError, ModelFileError
from hydro_sdp.io.documents import load_yaml, read_text
import pytest


def test_read_text_returns_the_text_and_drops_a_byte_order_mark_only_when_asked(tmp_path):
    path = tmp_path / 'a.csv'
    path.write_bytes(b'\xef\xbb\xbftime,angle\n')
    assert read_text(path) == '\ufefftime,angle\n'
    assert read_text(path, byte_order_mark=True) == 'time,angle\n'


def test_read_text_failures_name_the_file(tmp_path):
    with pytest.raises(ModelFileError) as caught:
        read_text(tmp_path / 'absent.yaml')
    assert str(caught.value) == f'{tmp_path / "absent.yaml"}: no such file'
    with pytest.raises(DataError) as caught:
        read_text(tmp_path, DataError, kind='a CSV file')
    assert str(caught.value) == f'{tmp_path} is a directory, not a CSV file'
    binary = tmp_path / 'b.yaml'
    binary.write_bytes(b'format: 1\n\xff\n')
    with pytest.raises(ModelFileError) as caught:
        read_text(binary)
    assert str(caught.value) == f'{binary}: not UTF-8 text (byte 10)'


def test_load_yaml_reads_through_read_text(tmp_path):
    with pytest.raises(ModelFileError, match=r'is a directory, not a file$'):
        load_yaml(tmp_path)
    path = tmp_path / 'c.yaml'
    path.write_text('a: [1, 2]\n', encoding='utf-8')
    assert load_yaml(path) == {'a': [1, 2]}

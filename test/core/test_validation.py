"""The shared readers of parsed files: each refusal names the key and the reason."""

from dataclasses import dataclass
import math

from hydro_sdp.core.errors import ConfigurationError, ModelFileError
from hydro_sdp.core.validation import read_document, require_mapping, require_positive_fields
import pytest

FORMAT = 'hydro_sdp/example/v1'


def test_read_document_returns_the_mapping_it_accepts():
    data = {'format': FORMAT, 'a': 1}
    assert read_document(data, 'an example file', FORMAT, ('format', 'a', 'b'), ('a',)) is data


@pytest.mark.parametrize(('data', 'message'), [
    ([1, 2], 'an example file must be a mapping of keys, got list'),
    ({'format': FORMAT, 'c': 1}, "unknown key 'c'"),
    ({'format': FORMAT, 3: 1}, 'unknown key 3'),
    ({'format': FORMAT}, "missing required key 'a'"),
    ({'a': 1}, "key 'format': expected 'hydro_sdp/example/v1', got None"),
    ({'format': 'v0', 'a': 1}, "key 'format': expected 'hydro_sdp/example/v1', got 'v0'"),
])
def test_read_document_refusals(data, message):
    with pytest.raises(ModelFileError) as caught:
        read_document(data, 'an example file', FORMAT, ('format', 'a'), ('a',))
    assert str(caught.value) == message


def test_unknown_keys_are_reported_before_missing_ones():
    with pytest.raises(ModelFileError, match="^unknown key 'x'$"):
        read_document({'x': 1}, 'a file', FORMAT, ('format', 'a'), ('format', 'a'))


@pytest.mark.parametrize(('value', 'expected', 'message'), [
    ('text', 'a mapping of keys', "key 'links[1]': expected a mapping of keys"),
    (None, 'a mapping with joint', "key 'links[1]': expected a mapping with joint"),
    ({'joint': 'j', 'mass': 2}, 'a mapping of keys', 'unknown key links[1].mass'),
    ({'length': 2}, 'a mapping of keys', 'missing required key links[1].joint'),
])
def test_require_mapping_names_the_nested_key(value, expected, message):
    with pytest.raises(ModelFileError) as caught:
        require_mapping(value, 'links[1]', ('joint', 'length'), ('joint',), expected=expected)
    assert str(caught.value) == message


def test_require_mapping_returns_the_mapping_it_accepts():
    value = {'joint': 'j'}
    assert require_mapping(value, 'links[0]', ('joint', 'length'), ('joint',)) is value


@dataclass
class _Settings:
    gain: float = 1.0
    wait: float = 0.0


def test_require_positive_fields_accepts_positive_and_allowed_zero():
    require_positive_fields(_Settings(), ('gain',))
    require_positive_fields(_Settings(), ('gain', 'wait'), zero_allowed=True)


@pytest.mark.parametrize(('settings', 'zero_allowed', 'message'), [
    (_Settings(wait=0.0), False, 'wait must be a positive number, got 0.0'),
    (_Settings(gain=-2.0), False, 'gain must be a positive number, got -2.0'),
    (_Settings(gain=math.inf), True, 'gain must be a number >= 0, got inf'),
    (_Settings(wait=math.nan), True, 'wait must be a number >= 0, got nan'),
    (_Settings(gain=-1.0, wait=-1.0), True, 'gain must be a number >= 0, got -1.0'),
])
def test_require_positive_fields_names_the_first_bad_field(settings, zero_allowed, message):
    with pytest.raises(ConfigurationError) as caught:
        require_positive_fields(settings, ('gain', 'wait'), zero_allowed=zero_allowed)
    assert str(caught.value) == message

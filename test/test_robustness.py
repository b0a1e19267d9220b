"""
Readers and the core never fail with an untyped error (property-based).

The example budget is small in CI; set HYDRO_SDP_FUZZ_EXAMPLES to fuzz longer.
"""

import os
from pathlib import Path
import shutil

from hydro_sdp.bags import read_bag, write_bag
from hydro_sdp.core.errors import HydroSdpError
from hydro_sdp.core.identification.identify import identify
from hydro_sdp.core.model.joint_model import JointModel
from hydro_sdp.core.model.records import Record
from hydro_sdp.io.model_files import default_model_path, dump_model, load_model
from hypothesis import example, given, HealthCheck, settings, strategies as st
import numpy as np
import pytest
import yaml

#: Steps from rest, 1.5 s each, of several sizes in both directions (the paper's Fig. 1).
IDENTIFIABLE = [item for level in (2.0, -2.0, 3.5, -3.5, 5.0, -5.0, 8.0, -8.0)
                for item in ((0.0, 100), (level, 150))] + [(0.0, 100)]
EXAMPLES = int(os.environ.get('HYDRO_SDP_FUZZ_EXAMPLES', '60'))
FUZZ = settings(max_examples=EXAMPLES, deadline=None,
                suppress_health_check=[HealthCheck.function_scoped_fixture,
                                       HealthCheck.too_slow])
J2_TEXT = default_model_path().read_text()


def _mutations():
    lines = J2_TEXT.splitlines()
    return st.one_of(
        st.text(max_size=200),
        st.binary(max_size=200).map(lambda b: b.decode('latin-1')),
        st.tuples(st.integers(0, len(lines) - 1), st.text(max_size=40)).map(
            lambda change: '\n'.join(lines[:change[0]] + [change[1]] + lines[change[0] + 1:])),
        st.tuples(st.integers(0, len(J2_TEXT)), st.integers(0, len(J2_TEXT))).map(
            lambda cut: J2_TEXT[:min(cut)] + J2_TEXT[max(cut):]),
    )


def _same_document(text):
    """Whether ``text`` parses to the shipped model's document (the mutation changed nothing)."""
    try:
        return yaml.safe_load(text) == yaml.safe_load(J2_TEXT)
    except (yaml.YAMLError, ValueError):
        return False


@FUZZ
@given(_mutations())
@example(J2_TEXT)
@example(J2_TEXT.replace('\n', '\n\n'))
def test_model_reader_answers_a_model_or_a_typed_error(tmp_path_factory, text):
    path = tmp_path_factory.mktemp('model') / 'model.yaml'
    path.write_text(text, encoding='utf-8', errors='surrogatepass')
    if _same_document(text):
        # Nothing that matters changed: the reader must answer the shipped model.
        assert load_model(path) == load_model(default_model_path())
        return
    try:
        model = load_model(path)
    except HydroSdpError as error:
        assert '\n' not in str(error).strip()
        return
    assert isinstance(model, JointModel)


@FUZZ
@given(st.builds(dict, delay=st.floats(0.0, 1.0), lower=st.floats(-5.0, 0.0),
                 upper=st.floats(0.0, 5.0), speed=st.floats(0.1, 100.0),
                 curvature=st.floats(0.01, 10.0)))
def test_model_files_round_trip_exactly(tmp_path_factory, values):
    data = yaml.safe_load(J2_TEXT)
    data.update(delay=values['delay'], dead_zone=[values['lower'], values['upper']],
                saturation_velocity=[-values['speed'], values['speed']],
                curvature=[values['curvature'], 2 * values['curvature']])
    model = JointModel.from_mapping(data)
    assert JointModel.from_mapping(yaml.safe_load(dump_model(model))) == model


SMALL = Record(np.arange(1, 301) * 0.01, np.sin(np.arange(1, 301) * 0.01),
               np.cos(np.arange(1, 301) * 0.01), joint='j2')


@pytest.fixture(scope='module')
def small_bag(tmp_path_factory):
    return write_bag(tmp_path_factory.mktemp('bag') / 'bag', [SMALL])


@FUZZ
@given(st.lists(st.tuples(st.floats(0.0, 1.0), st.integers(0, 255)), min_size=1, max_size=8))
@example(flips=[(0.7826088010331562, 0)])  # once: a NULL time stamp reached numpy
@example(flips=[(0.0, ord('S'))])           # the sqlite3 header's first byte, unchanged
def test_bag_reader_answers_records_or_a_typed_error(tmp_path_factory, small_bag, flips):
    copy = tmp_path_factory.mktemp('damaged') / 'bag'
    shutil.copytree(small_bag, copy)
    storage = next(p for p in Path(copy).iterdir() if p.suffix == '.db3')
    original = storage.read_bytes()
    data = bytearray(original)
    for where, value in flips:
        data[int(where * (len(data) - 1))] = value
    storage.write_bytes(bytes(data))
    if bytes(data) == original:
        # No byte changed: the reader must give back the record written.
        record = read_bag(copy).record()
        assert np.allclose(record.y, SMALL.y, rtol=0, atol=1e-9)   # via radians
        assert np.array_equal(record.v, SMALL.v)
        return
    try:
        record = read_bag(copy).record()
    except HydroSdpError as error:
        assert str(error)
        return
    assert len(record) > 0 and np.all(np.isfinite(record.y))


@settings(max_examples=max(10, EXAMPLES // 6), deadline=None)
@given(st.lists(st.tuples(st.floats(-6.0, 6.0), st.integers(5, 200)), min_size=1,
                max_size=30), st.floats(0.0, 0.2))
@example(levels=[(-1.34375, 19), (0.0, 72), (2.0, 20)], noise=0.0)  # once: empty side in fit
@example(levels=IDENTIFIABLE, noise=0.02)
def test_identification_returns_a_valid_model_or_a_typed_error(levels, noise):
    model = load_model(default_model_path())
    v = np.concatenate([np.full(n, level) for level, n in levels])
    from hydro_sdp.core.model.simulation import simulate
    y = simulate(model, v, 0.01, 25.0) + np.random.default_rng(0).normal(0.0, noise, v.size)
    record = Record(np.arange(1, v.size + 1) * 0.01, v, y, joint='j2')
    if levels == IDENTIFIABLE:
        # Steps from rest of several sizes in both directions: this one must identify.
        result = identify([record])
    else:
        try:
            result = identify([record])
        except HydroSdpError as error:
            assert str(error)
            return
    assert JointModel.from_mapping(result.model.to_mapping()) == result.model

"""Rows of the SDP analysis: each increment with its delayed command and its states."""

from hydro_sdp.core.errors import ConfigurationError, DataError
from hydro_sdp.core.identification.state_dependence.states import rows_of
from hydro_sdp.core.model.records import Record
import numpy as np
import pytest

DT = 0.01


def test_each_increment_gets_its_delayed_command_and_states():
    n = 12
    t = 1.76e9 + DT * np.arange(1, n + 1)
    v = np.array([0.0, 0.0, 2.0, 2.0, 2.0, -1.0, -1.0, -1.0, 0.0, 0.0, 0.0, 0.0])
    y = np.cumsum(np.arange(n, dtype=float))
    load = 100.0 + np.arange(n)
    other = 5.0 * np.arange(n)[:, None]      # the other joint at 500 deg/s
    record = Record(t, v, y, 'arm', 'run', origin=1.76e9, load=load, others=other,
                    other_joints=('boom',))
    rows = rows_of([record], delay=2, rest=0.0)
    k = np.arange(2, n)
    np.testing.assert_array_equal(rows.y, y[k])
    np.testing.assert_array_equal(rows.previous, y[k - 1])
    np.testing.assert_array_equal(rows.command, v[k - 2])
    np.testing.assert_array_equal(rows.increment, y[k] - y[k - 1])
    np.testing.assert_array_equal(rows.load, load[k - 1])
    np.testing.assert_allclose(rows.others_speed[2:], 500.0, rtol=1e-5)  # stamps near 1.76e9
    # The delayed command changes at rows 2 (to 2), 5 (to -1) and 8 (to 0): the time since
    # then counts from the sample before the change, so the first increment under it is dt.
    np.testing.assert_allclose(rows.since_change[[2, 3, 4, 5, 8, 9]],
                               [DT, 2 * DT, 3 * DT, DT, DT, 2 * DT], atol=1e-6)
    # The angle one sample before the increment: not the sample whose noise is in it.
    np.testing.assert_array_equal(rows.state('angle'), y[k - 2])
    with pytest.raises(ConfigurationError, match="unknown state 'speed'"):
        rows.state('speed')


def test_missing_signals_and_short_records_are_named():
    t = DT * np.arange(1, 6)
    record = Record(t, np.ones(5), np.arange(5.0), 'arm')
    rows = rows_of([record], delay=2, rest=0.0)
    with pytest.raises(DataError, match='no other joints'):
        rows.state('others_speed')
    with pytest.raises(DataError, match='no load signal'):
        rows.state('load')
    with pytest.raises(DataError, match='shorter than the delay'):
        rows_of([record], delay=4, rest=0.0)
    with pytest.raises(DataError, match='at least one sample'):
        rows_of([record], delay=0, rest=0.0)

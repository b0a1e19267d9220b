"""The nominal sample period of stamps as timers write them, and delays written cleanly."""

import math

from hydro_sdp.core.errors import DataError
from hydro_sdp.core.model.records import Record
from hydro_sdp.core.model.sample_period import (
    nominal_period, period_of_stamps, RELATIVE_FLOOR, round_within, whole_samples_seconds)
import numpy as np
import pytest

EPOCH = 1_760_000_000 * 10 ** 9


def timer(period, samples, jitter, seed):
    """Integer nanosecond stamps of a timer on a wall clock, jittered uniformly +-``jitter``."""
    rng = np.random.default_rng(seed)
    k = np.arange(samples)
    return EPOCH + np.round((k * period + rng.uniform(-jitter, jitter, samples)) * 1e9).astype(
        np.int64)


@pytest.mark.parametrize('samples', [60, 300, 6000])
@pytest.mark.parametrize('seed', [0, 1, 2])
def test_a_100_hz_timer_with_half_a_millisecond_of_jitter_is_read_as_0_01(samples, seed):
    stamps = timer(0.01, samples, 0.5e-3, seed)
    assert period_of_stamps(stamps) == 1e7          # ns, exactly
    relative = (stamps - stamps[0]) * 1e-9
    assert period_of_stamps(relative) == 0.01
    # What float seconds since 1970 would have given: the spacings quantised at 0.24 us,
    # and still 0.01 s.
    assert period_of_stamps(stamps * 1e-9) == 0.01


@pytest.mark.parametrize(('period', 'expected'), [(0.0125, 0.0125), (0.02, 0.02),
                                                  (0.005, 0.005), (0.1, 0.1)])
def test_other_timers_keep_their_own_period(period, expected):
    stamps = timer(period, 2000, 0.5e-3 * min(1.0, period / 0.01), 7)
    assert period_of_stamps((stamps - stamps[0]) * 1e-9) == expected


def test_a_period_the_data_pin_down_is_not_rounded_away():
    # 30 Hz: no short decimal lies within the stamps' precision; the period keeps the
    # digits that matter (within 100 ppm, a quartz clock's drift).
    t = np.arange(3000) / 30.0
    assert abs(period_of_stamps(t) - 1.0 / 30.0) <= 1.001 * RELATIVE_FLOOR / 30.0
    assert period_of_stamps(t) != 0.03
    # A clock 0.5 % slow is not taken for 0.01 s.
    assert period_of_stamps(np.arange(3000) * 0.01005) == 0.01005
    # A quartz drift of 30 ppm is below what matters: the nominal period.
    assert period_of_stamps(np.arange(3000) * 0.01 * (1 + 30e-6)) == 0.01


def test_holes_and_doubled_stamps_do_not_move_the_period():
    stamps = timer(0.01, 1000, 0.3e-3, 3)
    holed = np.r_[stamps[:400], stamps[410:]]
    assert period_of_stamps(holed) == 1e7
    steps = np.diff(stamps * 1e-9)
    steps[::50] = 0.02         # a sample lost now and then
    assert nominal_period(steps) == 0.01


def test_no_spacing_is_refused():
    with pytest.raises(DataError, match='at least two'):
        nominal_period(np.array([]))
    with pytest.raises(DataError, match='no positive sample period'):
        nominal_period(np.array([0.0, 0.0, 0.0]))


def test_round_within():
    assert round_within(0.0099994, 1e-5) == 0.01
    assert round_within(0.0125003, 1e-6) == 0.0125
    assert round_within(math.pi, 0.0) == math.pi


@pytest.mark.parametrize(('samples', 'dt', 'text'), [(12, 0.01, '0.12'), (15, 0.01, '0.15'),
                                                     (3, 0.05, '0.15'), (12, 0.0125, '0.15'),
                                                     (7, 0.001, '0.007'), (41, 0.01, '0.41')])
def test_delays_are_written_cleanly(samples, dt, text):
    assert repr(whole_samples_seconds(samples, dt)) == text


def test_records_give_the_nominal_period():
    stamps = timer(0.01, 500, 0.5e-3, 4)
    t = (stamps - (stamps[0] // 10 ** 9) * 10 ** 9) * 1e-9
    record = Record(t, np.zeros(500), np.zeros(500))
    assert record.sample_period == 0.01

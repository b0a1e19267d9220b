"""Identification from steps that reach an end stop and steps that push into one."""

from hydro_sdp.core.identification.end_stops import pushes_into_stop
from hydro_sdp.core.identification.identify import identify
from hydro_sdp.core.identification.map_fit import pwl_layout
from hydro_sdp.core.identification.segmentation import segment_records
from hydro_sdp.core.model.joint_model import JointModel
from hydro_sdp.core.model.records import Record
from hydro_sdp.core.model.simulation import simulate
from hydro_sdp.core.model.static_maps import PwlMap, SdpMap
import numpy as np
import pytest

#: J2 of the shipped config/brokk_j2.yaml (West et al. 2018).
TRUTH = SdpMap((-1.3298, 1.3124), (-29.51, 38.87), (1.356, 1.771))
LIMITS = (-13.8, 63.6)
J2 = JointModel('arm', TRUTH, 0.15, angle_limits=LIMITS, input_limits=(-10.0, 10.0))
#: Levels of the steps that travel from stop to stop (up, down).
MOVING = ((2.0, -2.2), (2.4, -2.6), (3.0, -3.0), (4.0, -4.0), (6.0, -6.0))
#: Larger levels driven into the stop the joint already sits at.
PUSHING = (8.0, 10.0)


def stop_record(seed: int) -> Record:
    """
    Rest 1 s, then for each pair: up to the upper stop, push into it, down, push.

    Every push starts at the stop it drives into; the next move starts there
    too but leaves it.
    """
    pieces = [np.zeros(100)]
    for index, (up, down) in enumerate(MOVING):
        push = PUSHING[index % len(PUSHING)]
        for level in (up, push, down, -push):
            pieces += [np.full(500, level), np.zeros(100)]
    v = np.concatenate(pieces)
    rng = np.random.default_rng(seed)
    y = simulate(J2, v, 0.01, 20.0) + rng.normal(0.0, 0.02, v.size)
    return Record(np.arange(1, v.size + 1) * 0.01, v, y, joint='arm', source=f'stops{seed}')


@pytest.fixture(scope='module')
def records() -> list[Record]:
    return [stop_record(seed) for seed in (1, 2)]


def test_steps_pushing_into_a_stop_are_dropped_with_the_reason(records: list[Record]) -> None:
    segmentation = segment_records(records, max_delay=50)
    held = [d for d in segmentation.dropped if d.reason == 'held against an end stop']
    # Two pushes per pair (one into each stop), every pair, both records.
    assert len(held) == 2 * len(MOVING) * len(records)
    pushes = {(r.source, round(float(r.t[k]), 2)) for r in records
              for k in np.flatnonzero(np.abs(np.diff(r.v)) > 0) + 1
              if abs(r.v[k]) in PUSHING}
    assert {(d.source, round(d.t0 + 0.01, 2)) for d in held} == pushes
    # The moves are kept, those from a stop away from it too; no push stays.
    levels = sorted(e.level for e in segmentation.experiments)
    assert levels == sorted(2 * [level for pair in MOVING for level in pair])
    np.testing.assert_allclose(np.array(segmentation.end_stops, dtype=float),
                               LIMITS, atol=0.1)


def test_identified_as_sdp_with_j2s_coefficients(records: list[Record]) -> None:
    result = identify(records)
    assert result.model.kind == 'sdp'
    fitted = result.model.static_map
    assert isinstance(fitted, SdpMap)
    np.testing.assert_allclose(fitted.dead_zone, TRUTH.dead_zone, rtol=0.02)
    np.testing.assert_allclose(fitted.saturation_velocity, TRUTH.saturation_velocity,
                               rtol=0.02)
    np.testing.assert_allclose(fitted.curvature, TRUTH.curvature, rtol=0.02)
    assert result.model.delay == pytest.approx(0.15)
    # No level outside the dead-zone is measured standing still (the rest tails are 0).
    moving = [p for p in result.points if p.level != 0.0]
    assert len(moving) == 4 * len(MOVING)
    assert all(abs(p.speed) > 20.0 for p in moving)
    assert sum(d.reason == 'held against an end stop'
               for d in result.segmentation.dropped) == 20


def test_pwl_fits_repeated_levels(records: list[Record]) -> None:
    result = identify(records, kind='pwl')
    assert result.model.kind == 'pwl'
    levels = np.array([level for pair in MOVING for level in pair])
    np.testing.assert_allclose(result.model.static_map.rate(levels),
                               J2.static_map.rate(levels), rtol=0.03)


def test_pwl_knots_stay_increasing_beyond_a_far_plateau_edge() -> None:
    # An sdp fit to data without a moving positive level put its edge at 5e21:
    # a knot 1 past it rounded back onto the edge.
    levels = np.array([-10.8, -9.0, -5.0, -3.0, 0.0, 3.0, 3.6, 5.0, 9.0, 10.8])
    layout = pwl_layout(levels, (-1.9e-22, 5.2e21))
    assert np.all(np.diff(layout.knots) > 0.0)
    assert layout.negative == 4 and layout.positive == 1
    speeds = layout.speeds(np.ones(layout.negative + layout.positive))
    static_map = PwlMap(tuple(layout.knots.tolist()), tuple(speeds.tolist()))
    assert static_map.rate(np.array([-10.8, 5.0]))[0] == pytest.approx(-4.0)
    assert static_map.rate(np.array([5.0]))[0] == 0.0


def test_held_only_when_at_the_stop_and_driven_into_it() -> None:
    stops = (-13.8, 63.6)
    at_top = np.full(50, 63.55)
    assert pushes_into_stop(at_top, 5.0, 0.0, stops)
    assert not pushes_into_stop(at_top, -5.0, 0.0, stops)       # driven away
    assert not pushes_into_stop(at_top, 5.0, 0.0, (-13.8, None))  # stop unknown
    # Starting 3 deg short: more than the tolerance (2 % of 77.4 deg) away.
    assert not pushes_into_stop(np.linspace(60.6, 63.6, 50), 5.0, 0.0, stops)
    # Starting at the lower stop, driven down: held; driven up: a move.
    assert pushes_into_stop(np.full(50, -13.7), -7.0, 0.0, stops)
    assert not pushes_into_stop(np.linspace(-13.8, 10.0, 50), 7.0, 0.0, stops)

"""The recalibration decision: significance, settling, thresholds, cooldown, the IDZ."""

from dataclasses import replace

from hydro_sdp.core.control.idz_design import idz_for_model
from hydro_sdp.core.control.idz_recalibration import (
    recalibrated_idz, Recalibration, RecalibrationPolicy)
from hydro_sdp.core.errors import ConfigurationError
from hydro_sdp.core.identification.online import SdpEstimate
import pytest

REFERENCE = (-1.3298, 1.3124)


def _estimate(lower, upper, std_lower=0.01, std_upper=0.01):
    return SdpEstimate(lower, upper, -29.51, 38.87, 1.356, 1.771,
                       std_lower, std_upper, 0.5, 0.5, 0.05, 0.05)


def _feed(decider, estimates, start=0.0, period=0.1):
    """Observe each estimate at ``period`` intervals; return the decisions."""
    return [decider.observe(start + k * period, e) for k, e in enumerate(estimates)]


def test_an_unchanged_joint_never_needs_recalibrating():
    decider = Recalibration(REFERENCE)
    # Estimates wander by up to 2.5 of their standard deviations around the reference.
    wander = [0.025 * ((k % 11) - 5) / 5 for k in range(600)]
    decisions = _feed(decider, [_estimate(-1.3298 + w, 1.3124 - w) for w in wander])
    assert not any(d.needed or d.due for d in decisions)
    assert decisions[-1].edges == REFERENCE


def test_a_settled_significant_change_moves_only_that_edge():
    decider = Recalibration(REFERENCE)
    decisions = _feed(decider, [_estimate(-1.3298, 1.0124, 0.01, 0.03)] * 21)
    # z = 0.3 / 0.03 = 10 from the first estimate, but it must hold for 2 s first.
    assert decisions[0].z[1] == pytest.approx(10.0)
    assert not any(d.needed for d in decisions[:20])
    assert decisions[20].needed and decisions[20].due
    assert decisions[20].edges == (-1.3298, 1.0124)       # the lower edge keeps its value


def test_an_estimate_still_on_its_way_is_not_acted_on():
    decider = Recalibration(REFERENCE)
    # The edge moves 0.02 V per second with a std of 0.01: always significant, never settled.
    moving = [_estimate(-1.3298 + 0.002 * k, 1.3124) for k in range(100)]
    decisions = _feed(decider, moving)
    assert decisions[-1].z[0] > 10.0 and not any(d.needed for d in decisions)
    # Once it stays within its std for the settle time, it is taken.
    still = [_estimate(-1.0298 + 0.008 * (k % 2), 1.3124) for k in range(21)]
    decisions = _feed(decider, still, start=10.0)
    assert not decisions[19].needed and decisions[20].needed
    assert decisions[20].edges == (-1.0298, 1.3124)


@pytest.mark.parametrize('std, needed', [(0.05, True), (0.09, True), (0.11, False),
                                         (0.2, False)])
def test_the_same_change_counts_only_if_large_next_to_the_estimate_std(std, needed):
    # A 0.3 V change: z = 6, 3.3, 2.7, 1.5; the decision scales with the noise.
    decider = Recalibration(REFERENCE)
    decisions = _feed(decider, [_estimate(-1.0298, 1.3124, std, 0.01)] * 21)
    assert decisions[-1].needed is needed


def test_min_change_and_confidence_bound_the_decision():
    tiny = Recalibration(REFERENCE)
    # 0.02 V at a std of 0.001 is significant (z = 20) but below min_change 0.03 V.
    assert not _feed(tiny, [_estimate(-1.3098, 1.3124, 0.001)] * 21)[-1].needed
    assert _feed(Recalibration(REFERENCE, RecalibrationPolicy(min_change=0.01)),
                 [_estimate(-1.3098, 1.3124, 0.001)] * 21)[-1].needed
    # A 1 V change at std 0.3: z = 3.3, but the std is 0.3 / 1.64 = 18 % of the dead-zone.
    vague = [_estimate(-0.3298, 1.3124, 0.3)] * 21
    assert not _feed(Recalibration(REFERENCE), vague)[-1].needed
    assert _feed(Recalibration(REFERENCE, RecalibrationPolicy(confidence=0.2)),
                 vague)[-1].needed


def test_cooldown_and_accepted_edges():
    decider = Recalibration(REFERENCE, RecalibrationPolicy(cooldown=5.0))
    worn = _estimate(-1.0298, 1.0124, 0.03, 0.03)
    decision = _feed(decider, [worn] * 21)[-1]
    assert decision.due and decision.edges == (-1.0298, 1.0124)
    decider.attempted(2.0)
    # Refused or unanswered: still needed, due again only 5 s after the attempt.
    assert decider.observe(6.9, worn).needed and not decider.observe(6.95, worn).due
    assert decider.observe(7.0, worn).due
    decider.accepted(decision.edges)
    assert decider.reference == (-1.0298, 1.0124)
    assert not decider.observe(7.1, worn).needed
    # A policy replaced at run time counts at the next estimate.
    decider.policy = replace(decider.policy, min_change=0.5)
    decider.accepted(REFERENCE)
    assert not decider.observe(7.2, worn).needed


def test_time_going_back_restarts_the_settle_time():
    decider = Recalibration(REFERENCE)
    assert _feed(decider, [_estimate(-1.0298, 1.3124, 0.03)] * 21, start=100.0)[-1].needed
    # A bag replayed from its start: 2 s of history are needed again.
    assert not decider.observe(0.0, _estimate(-1.0298, 1.3124, 0.03)).needed
    assert decider.observe(2.0, _estimate(-1.0298, 1.3124, 0.03)).needed


def test_edges_crossing_over_are_not_proposed():
    decider = Recalibration((-0.1, 0.1))
    assert not _feed(decider, [_estimate(0.5, 0.1, 0.01)] * 21)[-1].needed


@pytest.mark.parametrize('name, value', [('significance', 0.0), ('confidence', -1.0),
                                         ('settle', -1.0), ('min_change', float('nan')),
                                         ('cooldown', float('inf'))])
def test_policy_refuses_bad_thresholds(name, value):
    with pytest.raises(ConfigurationError, match=name):
        RecalibrationPolicy(**{name: value})


def test_the_idz_has_the_decided_edges_and_the_estimated_slopes(j2):
    edges = (-1.0298, 1.3124)
    idz = recalibrated_idz(j2, edges, 0.05)
    shifted = replace(j2, static_map=replace(j2.static_map, dead_zone=edges))
    assert idz.dead_zone == edges
    assert idz.slopes == idz_for_model(shifted, 0.05).slopes
    # The chord over a narrower dead-zone starts nearer the middle: a smaller lower slope.
    assert idz.slopes[0] < idz_for_model(j2, 0.05).slopes[0]
    assert idz.slopes[1] == pytest.approx(idz_for_model(j2, 0.05).slopes[1])

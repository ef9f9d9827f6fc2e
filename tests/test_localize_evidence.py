"""What counts as proof for a merge, and what a disturbed edge length can still refute.

A false merge corrupts the map for good, so the evidence rules are pinned here: a dead end
confirms less than a meet point (every dead end looks alike; fig16's mirror-image corridors
agree on them), a hypothesis that began off the graph needs one confirmation more, so does
one chosen among a crowd of look-alikes, and an edge on which the robot left the GVG and came
back is only a lower bound on the length.
"""

from __future__ import annotations

import pytest

from tslam.core.localize import Hypothesis, Tolerances


@pytest.mark.parametrize(
    ("confirmed", "dead_ends", "lost_start", "proven"),
    [
        (2, 0, False, True),  # the paper's Fig. 12: two predicted meet points found
        (1, 0, False, False),
        (1, 1, False, False),  # a dead end is half a confirmation
        (1, 2, False, True),
        (0, 4, False, False),  # dead ends alone never prove a place
        (2, 0, True, False),  # off the graph: one more
        (3, 0, True, True),
        (2, 2, True, True),
    ],
)
def test_merge_evidence(confirmed, dead_ends, lost_start, proven):
    h = Hypothesis({7: (3, 0)}, confirmed=confirmed, dead_ends=dead_ends, lost_start=lost_start)
    assert h.proven(merge_evidence=2) is proven
    assert h.tested is (confirmed + dead_ends > 0)


def test_a_disturbed_length_refutes_only_when_too_short():
    tol = Tolerances(length_abs_m=0.35, length_rel=0.12)
    bound = Tolerances(length_abs_m=0.35, length_rel=0.12, at_least=True)
    mapped = 5.0  # slack 0.35 + 0.6 = 0.95 m
    assert tol.length_ok(5.9, mapped) and bound.length_ok(5.9, mapped)
    assert not tol.length_ok(8.0, mapped)  # a detour of 3 m: refuted by the two-sided test
    assert bound.length_ok(8.0, mapped)  # ... but wandering only ever adds length
    assert not bound.length_ok(3.9, mapped)  # shorter than the edge can be: still refuted
    assert tol.length_ok(None, mapped) and bound.length_ok(None, mapped)


def test_a_disturbed_length_is_longer_by_no_more_than_the_robot_drove_off_the_edge():
    # fig12 seed 5: back from a dead end at the end of a 1.3 m edge, 0.08 m off the edge on
    # the way, the robot went through the junction unhomed and measured 6.5 m to the next.
    bound = Tolerances(length_abs_m=0.25, length_rel=0.08, at_least=True, wandered_m=0.08)
    mapped = 1.3  # slack 0.25 + 0.104 m
    assert not bound.length_ok(6.5, mapped)
    assert bound.length_ok(1.3 + 0.354 + 0.08, mapped)
    assert not bound.length_ok(1.3 + 0.354 + 0.09, mapped)
    assert not bound.length_ok(0.9, mapped)  # too short stays refuted


@pytest.mark.parametrize(
    ("crowd", "needed"),
    [
        (1, 2),  # one look-alike: the paper's two confirmations
        (4, 2),
        (5, 3),  # more than two bits of prior odds against each: one more
        (16, 3),
        (37, 4),  # a trial build's fig14 seed 4 merged 3 places wrong among 37 look-alikes
        (73, 5),  # ... and its fig15 seed 3, among 73
    ],
)
def test_a_map_crowded_with_look_alikes_needs_more_evidence(crowd, needed):
    def proven(confirmed: int) -> bool:
        return Hypothesis({7: (3, 0)}, confirmed=confirmed, crowd=crowd).proven(2)

    assert proven(needed) and not proven(needed - 1)

"""Out of one point of a close pair and onto the other: recognised, not mapped again.

fig13 seed 5 at drift paper. At 410 s the robot left true meet point 2 by its departure to a
dead end, swung onto the 0.53 m edge to true meet point 3 and homed there after 0.57 m: which
departure it went out by was asked of the way 0.8 m out (``left_by_m``), which it never
reached, and meet point 3 went into the map again. Now the bearing to where it stands says
(``left_by_short_m``). At 989 s it went 0.45 m out of the 0.29 m pair of true meet points 4
and 6 and back, homed 0.35 m from where it had left, and read the place's four edges as
before: further than a bounce (``bounce_m``, 0.2 m), it was mapped again. Now a bounce reaches
as far as the place's other point (``bounce_place_m``), the bearings telling a twin junction.
"""

from __future__ import annotations

from tests.explored import explored


def _run(duration_s: float, **changes: float) -> tuple[dict, list[str]]:
    rep, notes, _ = explored("fig13", 5, "paper", duration_s, changes)
    return rep, notes


def test_the_short_way_out_recognises_the_pairs_other_point():
    rep, notes = _run(420.0)
    assert any("not held: went another way, recognised node" in t for t in notes)
    assert rep["duplicate_nodes"] == 0 and rep["false_merges"] == 0


def test_without_the_short_way_out_the_other_point_is_mapped_twice():
    rep, _ = _run(420.0, left_by_short_m=0.0)
    assert rep["duplicate_nodes"] >= 1


def test_back_at_the_places_other_point_is_a_bounce():
    rep, notes = _run(1000.0)
    assert any("could not be held" in t for t in notes)
    assert rep["duplicate_nodes"] == 0 and rep["false_merges"] == 0


def test_without_the_places_reach_the_place_is_mapped_again():
    rep, _ = _run(1000.0, bounce_place_m=0.0)
    assert rep["duplicate_nodes"] >= 1

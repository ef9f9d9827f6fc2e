"""Out along a departure that is no edge, back through the node, and on along a mapped edge.

fig13 seed 4 at drift paper: true meet point 0 (degree 3) was first read with a fourth edge,
east. At 958 s the robot left by it, found no edge there, came back through the node 0.9 m
later and went on along its edge south, to true meet point 1. Which departure it had gone
out by was read from the first point of its way 0.8 m out, on the way east: a new place, it
was mapped again, and the copies multiplied. Now the way out is read from the last time the
way passed the node (``left_by_back_m``): node 1 is recognised, the departure that could not
be held is tried again and given up.
"""

from __future__ import annotations

from tests.explored import explored


def _run(**changes: float) -> tuple[dict, list[str]]:
    rep, notes, _ = explored("fig13", 4, "paper", 1000.0, changes)
    return rep, notes


def test_back_through_the_node_the_place_beyond_is_recognised():
    rep, notes = _run()
    assert "departure 3 of node 16 not held: went another way, recognised node 1" in notes
    assert rep["duplicate_nodes"] == 0 and rep["false_merges"] == 0


def test_read_from_the_way_east_it_is_mapped_again():
    rep, notes = _run(left_by_back_m=0.0)
    assert not any("of node 16 not held" in t for t in notes)
    assert rep["duplicate_nodes"] >= 1

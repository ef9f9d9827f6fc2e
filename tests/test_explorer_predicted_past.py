"""A reading one edge past the node a hypothesis predicts is not read as another place.

fig13 seed 3 without drift: at 961 s the hypothesis that the new nodes 28 and 29 were true
meet points 7 and 5, mapped as nodes 20 and 10, was confirmed once. Sent on from 29 toward
true meet point 3 (3.02 m), the robot went through it unhomed to its pair's other point,
true meet point 2, 0.53 m on (3.50 m in all, within the first edge's slack). A rival
hypothesis predicted node 2 there, the 0.29 m pair's place mapped with four edges, and the
reading (three edges) was taken for that place with an edge fewer (``predicted_place``). The
true hypothesis was refuted by that reading, and the lab went into the map again. Now a
hypothesis whose prediction the reading fits one edge further, even within the first
edge's slack (``past_within_slack``), keeps the reading as it is (``predicted_past``): the
hypothesis lives on with that edge cut, and the fragment is merged at 1053 s.
"""

from __future__ import annotations

import pytest

from tests.explored import explored


def _run(**changes: bool) -> tuple[dict, list[str]]:
    rep, notes, _ = explored("fig13", 3, "none", 1320.0, changes)
    return rep, notes


def test_one_edge_past_the_predicted_node_the_true_hypothesis_lives_and_merges():
    rep, notes = _run()
    assert not any(t.startswith("node 30, read with 3 edges, read as node 2") for t in notes)
    assert "loop closed: 28=20, 29=10, 30=16, 31=15, 32=1; 15 nodes, 16 edges" in notes
    assert rep["complete"] and rep["duplicate_nodes"] == 0 and rep["false_merges"] == 0


@pytest.mark.parametrize("switch", ["predicted_past", "past_within_slack"])
def test_without_either_rule_the_reading_is_taken_for_the_rivals_place(switch):
    rep, notes = _run(**{switch: False})
    assert any(t.startswith("node 30, read with 3 edges, read as node 2") for t in notes)
    assert rep["duplicate_nodes"] >= 1

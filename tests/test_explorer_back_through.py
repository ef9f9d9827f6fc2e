"""An edge whose way went out along another edge first and came back through the node.

fig13 seed 1 without drift: at 746 s the robot went past a junction unhomed and was lost, and
mapped true meet points 1, 0 and 2 anew. Sent from the second of them along one departure at
765 s, it traced 0.8 m of the next edge instead, came back 0.2 m past the junction and went on
along the first. Its length took in the way out and back: 3.25 m for an edge of 2.25. The
hypothesis that the three were the old meet points was confirmed at every arrival, but the
fragment could never be placed on the map with that edge (its length fits no edge there),
so it was never merged; lost again at 880 s, the robot mapped the lab over and over. The
edge now begins again where the way came back through the node (``TracerParams.edge_back_m``,
``edgelength.py``), and the fragment is merged at 824 s.
"""

from __future__ import annotations

from tests.explored import explored


def _run(**changes: float) -> tuple[dict, list[str], dict[frozenset[int], tuple[float, ...]]]:
    rep, notes, run = explored("fig13", 1, "none", 830.0, tracer=changes)
    lengths = {frozenset((e.u, e.v)): e.lengths_m for e in run.explorer.map.edges()}
    return rep, notes, lengths


def test_the_way_back_through_the_node_is_left_out_and_the_fragment_merges():
    rep, notes, lengths = _run()
    assert "loop closed: 23=1, 24=16, 25=14, 26=12; 18 nodes, 18 edges" in notes
    assert rep["duplicate_nodes"] == 0 and rep["false_merges"] == 0
    # Node 16 is true meet point 0, node 14 true meet point 2: 2.22 m apart along the edge.
    assert all(abs(x - 2.22) < 0.1 for x in lengths[frozenset((14, 16))])


def test_with_the_way_out_and_back_measured_the_fragment_stays_apart():
    rep, notes, lengths = _run(edge_back_m=0.0)
    assert not any(t.startswith("loop closed: 23=1") for t in notes)
    assert rep["duplicate_nodes"] >= 3
    assert len(lengths[frozenset((14, 16))]) == 1  # traced once: the second time went
    assert lengths[frozenset((24, 25))][0] > 3.0  # into its copy, with the way out and back

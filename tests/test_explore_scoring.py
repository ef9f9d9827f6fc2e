"""Scoring a map against the ground truth: coverage by places (close meet points are one)."""

from __future__ import annotations

import pytest

from sim_backend.builtin_worlds import builtin_world
from sim_backend.explore_scoring import places, score_exploration
from sim_backend.ground_truth import GroundTruthGVG, compute_gvg


@pytest.fixture(scope="module")
def gvgs() -> dict[str, GroundTruthGVG]:
    return {w: compute_gvg(builtin_world(w)) for w in ("fig12", "fig14", "fig16")}


def _map_of(gvg: GroundTruthGVG, skip_nodes=(), skip_edges=()) -> dict:
    """The true GVG written as a map, each node first visited exactly where it is."""
    nodes = [
        {"id": n.id, "kind": n.kind, "truth": {"x": n.x, "y": n.y}}
        for n in gvg.nodes
        if n.id not in skip_nodes
    ]
    kept = {n["id"] for n in nodes}
    edges = [
        {"u": e.u, "v": e.v, "length_m": e.length_m}
        for i, e in enumerate(gvg.edges)
        if i not in skip_edges and e.u in kept and e.v in kept
    ]
    return {"nodes": nodes, "edges": edges}


def test_a_close_pair_is_one_place_and_a_far_one_is_not(gvgs):
    place = places(gvgs["fig16"])
    meets = sorted(n.id for n in gvgs["fig16"].meet_points)
    # fig16's weak meet point is 0.36 m from the corridor's: one place of the four.
    assert len({place[m] for m in meets}) == len(meets) - 1
    place12 = places(gvgs["fig12"])
    assert len({place12[n.id] for n in gvgs["fig12"].meet_points}) == 3


def test_the_true_graph_covers_its_world_and_one_edge_less_does_not(gvgs):
    g = gvgs["fig12"]
    whole = score_exploration(g, _map_of(g), [])
    assert whole["covered"] and whole["found_places"] == whole["true_places"] == 3
    assert whole["found_place_edges"] == whole["true_place_edges"] == len(g.edges)
    # Every true edge counts: leaving any one out leaves the map incomplete.
    for i in range(len(g.edges)):
        less = score_exploration(g, _map_of(g, skip_edges={i}), [])
        assert not less["covered"], f"edge {i} left out"
        assert less["found_place_edges"] == len(g.edges) - 1


def test_a_junction_seen_as_one_where_two_meet_points_are_close_still_covers(gvgs):
    g = gvgs["fig14"]
    place = places(g)
    pairs = [(e.u, e.v) for e in g.edges if e.u != e.v and place[e.u] == place[e.v]]
    assert pairs, "fig14 has close meet points (0.26 m and 0.29 m apart)"
    u, v = pairs[0]
    # The robot homes onto u only: v's edges end at u in its map.
    m = _map_of(g, skip_nodes={v})
    for e in g.edges:
        if v in (e.u, e.v) and {e.u, e.v} != {u, v}:
            other = e.v if e.u == v else e.u
            m["edges"].append({"u": u, "v": other, "length_m": e.length_m})
    s = score_exploration(g, m, [])
    assert s["found_meet_points"] == s["true_meet_points"] - 1
    assert s["covered"]
    # Without the edges that went on from v, the place is there but the map is not whole.
    s2 = score_exploration(g, _map_of(g, skip_nodes={v}), [])
    assert s2["found_places"] == s2["true_places"] and not s2["covered"]


def test_an_edge_traced_past_a_junction_is_a_wrong_edge(gvgs):
    """fig12: an edge from one meet point to a node two edges on (the junction between
    passed without homing) joins two places the true GVG does not; the true map has none,
    and an edge within a close pair's place is no wrong edge either."""
    g = gvgs["fig12"]
    assert score_exploration(g, _map_of(g), [])["wrong_edges"] == 0
    nbrs = {n.id: set() for n in g.nodes}
    for e in g.edges:
        nbrs[e.u].add(e.v)
        nbrs[e.v].add(e.u)
    a = next(n.id for n in g.meet_points)
    far = next(c for b in nbrs[a] for c in nbrs[b] if c != a and c not in nbrs[a])
    m = _map_of(g)
    m["edges"].append({"u": a, "v": far, "length_m": 5.0})
    assert score_exploration(g, m, [])["wrong_edges"] == 1
    f16 = gvgs["fig16"]
    place = places(f16)
    u, v = next((e.u, e.v) for e in f16.edges if e.u != e.v and place[e.u] == place[e.v])
    m16 = _map_of(f16)
    m16["edges"].append({"u": u, "v": v, "length_m": 0.3})
    assert score_exploration(f16, m16, [])["wrong_edges"] == 0

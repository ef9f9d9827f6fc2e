"""The topological map: building, signatures, merging, planning, the reduced GVG, files, SVG."""

from __future__ import annotations

import copy
import json
import math
import os
import stat
import xml.etree.ElementTree as ET
from dataclasses import replace

import networkx as nx
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from tslam.core.signature import Signature, cyclic_gaps, rotations
from tslam.core.topomap import (
    TAU,
    EdgeConflictError,
    Likeness,
    Link,
    MapError,
    MapFormatError,
    Step,
    TopoMap,
)
from tslam.programs.cli import UserError
from tslam.programs.map_files import load_map, render_map_svg, save_map, save_map_svg

FUZZ = settings(
    max_examples=120,
    derandomize=True,
    database=None,
    deadline=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture],
)

# The paper's Fig. 12: a cycle of four meet points round an obstacle, listed counter-clockwise;
# from each, one edge runs out to a corner of the room.
RING = [(-2.0, -2.0), (2.0, -2.0), (2.0, 2.0), (-2.0, 2.0)]


def corner(m: TopoMap, i: int, drift: float = 0.0, clearance: float = 1.0):
    """Add ring meet point ``i`` as the robot would see it with its heading off by ``drift``;
    returns its id and which port points to the next corner, the previous one, and out."""
    x, y = RING[i]
    nxt, prv = RING[(i + 1) % 4], RING[(i - 1) % 4]
    true = {
        "next": math.atan2(nxt[1] - y, nxt[0] - x),
        "prev": math.atan2(prv[1] - y, prv[0] - x),
        "out": math.atan2(y, x),
    }
    seen = {k: (a + drift) % TAU for k, a in true.items()}
    order = sorted(seen, key=seen.get)
    n = m.add_meet(clearance, [seen[k] for k in order], pose=(x, y), truth=(x, y))
    return n, {k: order.index(k) for k in order}


def first_lap(m: TopoMap):
    """1 -> 2 -> 3 -> 4 as in Fig. 12; the edge from 4 back to 1 not yet traced."""
    nodes = [corner(m, i) for i in range(4)]
    for i, length in zip(range(3), (4.0, 4.1, 3.9), strict=True):
        (a, pa), (b, pb) = nodes[i], nodes[i + 1]
        m.connect(a, pa["next"], b, pb["prev"], length)
    return nodes


# -- building -------------------------------------------------------------------------------


def test_fig12_cycle_built_by_hand():
    m = TopoMap()
    nodes = first_lap(m)
    (n1, p1), (n4, p4) = nodes[0], nodes[3]
    closing = m.connect(n4, p4["next"], n1, p1["prev"], 4.05)
    assert [n.id for n in m.nodes()] == [1, 2, 3, 4]
    assert all(n.kind == "meet" and n.degree == 3 for n in m.nodes())
    assert len(nx.cycle_basis(nx.Graph(m.graph))) == 1
    assert m.unexplored() == [(n, p["out"]) for n, p in nodes]
    assert m.neighbours(n1) == sorted(
        [Link(p1["next"], 1, 2, nodes[1][1]["prev"]), Link(p1["prev"], closing, 4, p4["next"])]
    )
    # A port leads one way only: a second edge on it is a bookkeeping error, named clearly.
    with pytest.raises(MapError, match=rf"port {p1['next']} of node 1 is already taken by edge 1"):
        m.connect(n1, p1["next"], 3, 0, 1.0)
    with pytest.raises(MapError, match="node 1 has no port 3"):
        m.connect(n1, 3, 2, 0, 1.0)
    with pytest.raises(MapError, match="same port"):
        m.connect(n1, p1["out"], n1, p1["out"], 1.0)
    b = m.add_boundary(0.4, pose=(-3.0, -3.0), departure_rad=math.pi / 4)
    m.connect(n1, p1["out"], b, 0, 1.4)
    assert m.node(b).degree == 1 and m.node(b).ports == (5,)
    assert (n1, p1["out"]) not in m.unexplored()


def test_departures_must_be_counter_clockwise_and_finite():
    m = TopoMap()
    with pytest.raises(MapError, match="strictly ascending"):
        m.add_meet(1.0, [1.0, 0.5, 2.0], pose=(0, 0))
    with pytest.raises(MapError, match="outside"):
        m.add_meet(1.0, [0.5, 7.0], pose=(0, 0))
    with pytest.raises(MapError, match="finite"):
        m.add_meet(float("nan"), [0.5, 1.0], pose=(0, 0))
    assert m.version == 0 and m.nodes() == []


def test_every_change_is_logged_with_a_sequence_number():
    m = TopoMap()
    a = m.add_meet(1.0, [0.0, 2.0, 4.0], pose=(0, 0))
    b = m.add_boundary(0.4, pose=(1, 0))
    e = m.connect(a, 0, b, 0, 1.0)
    m.add_measurement(e, 1.2)
    m.set_ambiguous(a, [b])
    assert [c.seq for c in m.changes] == [1, 2, 3, 4, 5] and m.version == 5
    assert [c.op for c in m.changes] == [
        "node_added",
        "node_added",
        "edge_added",
        "measurement",
        "ambiguity",
    ]
    assert [c.seq for c in m.changes_since(3)] == [4, 5]
    assert m.changes[4].data == {"sets": [[a, [b]], [b, [a]]]}
    json.dumps([c.data for c in m.changes])  # publishable as is
    assert m.edge(e).lengths_m == (1.0, 1.2)
    m.set_ambiguous(a, [])
    assert m.node(b).ambiguous_with == frozenset() and m.version == 6


def test_the_estimate_is_the_median_of_the_measurements():
    m = TopoMap()
    a = m.add_meet(1.0, [0.0, 3.0], pose=(0, 0))
    b = m.add_meet(1.0, [0.0, 3.0], pose=(2, 0))
    e = m.connect(a, 0, b, 1, 2.0)
    m.add_measurement(e, 2.2)
    m.add_measurement(e, 9.0)  # a detour round a person: one bad traversal
    assert m.edge(e).length_m == 2.2
    assert m.graph.edges[a, b, e]["length_m"] == 2.2


def test_split_edge_puts_a_missed_junction_on_the_edge():
    m = TopoMap()
    w = m.add_meet(1.0, [0.0, 2.0, 4.0], pose=(4, 0))
    b = m.add_boundary(0.4, pose=(-0.5, -0.5))
    e = m.connect(w, 1, b, 0, 4.7)
    m.add_measurement(e, 4.9)
    j = m.add_meet(0.9, [0.5, 2.5, 4.5], pose=(0, 0))
    near, far = m.split_edge(e, b, 0, j, 2, 0, 0.7)
    with pytest.raises(MapError):
        m.edge(e)
    assert m.edge(near).lengths_m == (0.7,) and m.edge(far).length_m == pytest.approx(4.1)
    assert m.node(b).ports == (near,) and m.node(j).ports == (far, None, near)
    assert m.node(w).ports[1] == far
    assert [lk.node for lk in m.neighbours(j)] == [w, b]
    assert nx.has_path(m.graph, b, w) and not m.graph.has_edge(b, w)
    assert m.changes[-1].op == "edge_split" and m.changes[-1].data["edge"] == e
    json.dumps(m.changes[-1].data)
    assert m.unexplored() == [(w, 0), (w, 2), (j, 1)]


def test_a_meet_node_read_again_as_its_place_keeps_its_edges_on_their_bearings():
    m = TopoMap()
    n = m.add_meet(1.1, [math.pi / 2, math.pi, 3 * math.pi / 2], pose=(0, 0))
    up = m.add_boundary(0.4, pose=(0, 5))
    loop_meet = m.add_meet(1.0, [0.0, 1.0, 2.0], pose=(0, -5))
    e_up = m.connect(n, 0, up, 0, 5.0)
    e_down = m.connect(n, 2, loop_meet, 1, 5.0)
    place = [math.pi / 2, 3 * math.pi / 4, 5 * math.pi / 4, 3 * math.pi / 2]
    m.reread(n, place, 0.9, {0: 0, 2: 3})  # port 1 (west) led inside the place
    assert m.node(n).degree == 4 and m.node(n).clearance_m == 0.9
    assert m.node(n).ports == (e_up, None, None, e_down)
    assert m.edge(e_down).other_end(loop_meet, 1) == (n, 3)
    assert m.unexplored() == [(n, 1), (n, 2), (loop_meet, 0), (loop_meet, 2)]
    assert m.changes[-1].op == "node_reread"
    json.dumps(m.changes[-1].data)
    assert TopoMap.from_dict(m.to_dict()).node(n).ports == (e_up, None, None, e_down)


@pytest.mark.parametrize(
    ("carry", "why"),
    [({0: 0}, "port 2's edge"), ({0: 0, 2: 0}, "port 2's edge"), ({0: 0, 2: 4}, "port 2's edge")],
)
def test_reading_a_node_again_refuses_to_lose_an_edge(carry, why):
    m = TopoMap()
    n = m.add_meet(1.1, [1.0, 2.0, 3.0], pose=(0, 0))
    ends = [m.add_boundary(0.4, pose=(p, 1)) for p in (0, 2)]
    for p, b in zip((0, 2), ends, strict=True):
        m.connect(n, p, b, 0, 1.0)
    before = m.to_dict()
    with pytest.raises(MapError, match=why):
        m.reread(n, [0.5, 1.5, 2.5, 3.5], 1.0, carry)
    with pytest.raises(MapError, match="ascending"):
        m.reread(n, [1.5, 0.5, 2.5, 3.5], 1.0, {0: 0, 2: 2})
    with pytest.raises(MapError, match="boundary node"):
        m.reread(ends[0], [0.5], 1.0, {0: 0})
    assert m.to_dict() == before


@pytest.mark.parametrize(
    "ports, at, why",
    [
        ((2, 2), 0.7, "cannot split"),
        ((2, 3), 0.7, "no port 3"),
        ((2, 0), 4.8, "cannot split it at"),
    ],
)
def test_split_edge_refuses_what_cannot_be(ports, at, why):
    m = TopoMap()
    w = m.add_meet(1.0, [0.0, 2.0, 4.0], pose=(4, 0))
    b = m.add_boundary(0.4, pose=(-0.5, -0.5))
    e = m.connect(w, 1, b, 0, 4.7)
    j = m.add_meet(0.9, [0.5, 2.5, 4.5], pose=(0, 0))
    before = m.version
    with pytest.raises(MapError, match=why):
        m.split_edge(e, b, 0, j, *ports, at)
    assert m.version == before and m.edge(e).length_m == 4.7


def test_remove_node_frees_the_far_ports():
    m = TopoMap()
    nodes = first_lap(m)
    n2 = nodes[1][0]
    m.remove_node(n2)
    assert not m.has_node(n2) and [e.id for e in m.edges()] == [3]
    assert (1, nodes[0][1]["next"]) in m.unexplored()
    assert (3, nodes[2][1]["prev"]) in m.unexplored()
    assert m.changes[-1].op == "node_removed" and m.changes[-1].data["edges"] == [1, 2]


def test_remove_edge_frees_both_ports_and_says_so():
    m = TopoMap()
    nodes = first_lap(m)
    (n1, p1), (n2, p2) = nodes[0], nodes[1]
    e = m.node(n1).ports[p1["next"]]
    m.remove_edge(e)
    assert not m.has_edge(e) and m.has_node(n1) and m.has_node(n2)
    assert {(n1, p1["next"]), (n2, p2["prev"])} <= set(m.unexplored())
    assert m.changes[-1].op == "edge_removed" and m.changes[-1].data == {"edge": e}
    with pytest.raises(MapError, match=f"no edge {e}"):
        m.remove_edge(e)


# -- signatures -----------------------------------------------------------------------------


@pytest.mark.parametrize("drift", [0.0, 0.05, -0.3, 2.0, 3.5, -5.9])
def test_a_revisit_matches_under_the_right_rotation(drift):
    m = TopoMap()
    n1, p1 = corner(m, 0)
    n5, p5 = corner(m, 0, drift=drift, clearance=1.03)
    ks = m.signature_rotations(n5, n1, clearance_tol_m=0.1, angle_tol_rad=0.1)
    # The gaps are 90, 135, 135 degrees: only one shift lines them up.
    assert ks == [(p1["next"] - p5["next"]) % 3]
    k = ks[0]
    for label in ("next", "prev", "out"):
        assert (p5[label] + k) % 3 == p1[label]


def test_neighbouring_ring_corners_look_alike():
    # The paper's point: in Fig. 12 every ring meet point looks like every other.
    m = TopoMap()
    (n1, _), (n2, _) = corner(m, 0), corner(m, 1)
    assert m.signature_rotations(n1, n2, 0.1, 0.1) == [0]


def test_same_angles_in_another_order_do_not_match():
    # Fig. 11: B is A turned; C has A's angles in another cyclic order.
    a = Signature("meet", 1.0, (0.0, 1.0, 2.5))
    b = Signature("meet", 1.0, tuple(sorted((x + 0.7) % TAU for x in (0.0, 1.0, 2.5))))
    c = Signature("meet", 1.0, (0.0, 1.5, 2.5))
    assert sorted(cyclic_gaps(a.departures_rad)) == pytest.approx(
        sorted(cyclic_gaps(c.departures_rad))
    )
    assert rotations(a, b, 0.1, 0.05) == [0]
    assert rotations(a, c, 0.1, 0.05) == []


def test_degree_clearance_and_kind_must_agree():
    three = Signature("meet", 1.0, (0.0, 2.0, 4.0))
    four = Signature("meet", 1.0, (0.0, 1.5, 3.0, 4.5))
    assert rotations(three, four, 0.1, 0.2) == []
    assert rotations(three, Signature("meet", 1.3, (0.0, 2.0, 4.0)), 0.1, 0.2) == []
    assert rotations(three, Signature("meet", 1.08, (0.0, 2.0, 4.0)), 0.1, 0.2) == [0]
    lone = Signature("meet", 0.5, (1.0,))
    assert rotations(lone, Signature("boundary", 0.5, (2.0,)), 0.1, 0.2) == []
    assert rotations(
        Signature("boundary", 0.5, (4.0,)), Signature("boundary", 0.5, (2.0,)), 0.1, 0.2
    ) == [0]


def test_angle_tolerance_is_on_the_gaps():
    a = Signature("meet", 1.0, (0.0, 2.0, 4.0))
    bent = Signature("meet", 1.0, (0.0, 2.15, 4.0))  # one edge 0.15 rad off
    assert rotations(a, bent, 0.1, 0.1) == []
    assert rotations(a, bent, 0.1, 0.2) == [0]


def test_boundary_neighbours_must_agree_where_known():
    # Fig. 9: a symmetric Y fits itself three ways until its dead ends tell the ways apart.
    deps = (0.0, TAU / 3, 2 * TAU / 3)
    y = Signature("meet", 1.0, deps)
    assert rotations(y, y, 0.1, 0.1) == [0, 1, 2]
    # Unexplored ports rule nothing out: only two known answers that differ do.
    a = Signature("meet", 1.0, deps, (True, None, None))
    assert rotations(a, Signature("meet", 1.0, deps, (None, True, None)), 0.1, 0.1) == [0, 1, 2]
    a = Signature("meet", 1.0, deps, (True, False, False))
    assert rotations(a, Signature("meet", 1.0, deps, (None, True, None)), 0.1, 0.1) == [1]
    a = Signature("meet", 1.0, deps, (True, False, False))
    assert rotations(a, Signature("meet", 1.0, deps, (False, False, True)), 0.1, 0.1) == [2]
    assert rotations(a, Signature("meet", 1.0, deps, (True, True, False)), 0.1, 0.1) == []


def test_the_map_reports_which_ports_lead_to_boundaries():
    m = TopoMap()
    n1, p1 = corner(m, 0)
    n2, p2 = corner(m, 1)
    n5, p5 = corner(m, 0, drift=0.4)
    b1 = m.add_boundary(0.4, pose=(-3, -3))
    m.connect(n1, p1["out"], b1, 0, 1.4)
    assert m.signature(n1).to_boundary[p1["out"]] is True
    assert len(m.signature_rotations(n5, n1, 0.1, 0.1)) == 1  # nothing known about 5 yet
    m.connect(n1, p1["next"], n2, p2["prev"], 4.0)
    b5 = m.add_boundary(0.4, pose=(0, -3))
    m.connect(n5, p5["next"], b5, 0, 1.4)  # the revisit has a dead end where 1 goes on
    assert m.signature(n1).to_boundary == tuple(
        {"next": False, "prev": None, "out": True}[k] for k in sorted(p1, key=p1.get)
    )
    assert m.signature_rotations(n5, n1, 0.1, 0.1) == []


# -- merging ----------------------------------------------------------------------------------


def test_merge_reattaches_edges_through_the_rotation():
    m = TopoMap()
    n1, p1 = corner(m, 0)
    n2, p2 = corner(m, 1)
    e12 = m.connect(n1, p1["next"], n2, p2["prev"], 4.0)
    n5, p5 = corner(m, 0, drift=-0.3)  # first seen again from the other side
    b = m.add_boundary(0.4, pose=(-3, -3))
    e5b = m.connect(n5, p5["out"], b, 0, 1.4)
    m.set_ambiguous(n5, [n1, n2])
    (k,) = m.signature_rotations(n5, n1, 0.1, 0.1)
    before, frame = m.version, m.node(n1).departures_rad
    plan = m.merge(n1, n5, k)
    assert plan.nodes == {n5: (n1, k)} and plan.edges == {}
    assert not m.has_node(n5)
    edge = m.edge(e5b)
    assert (edge.u, edge.port_u) == (n1, p1["out"]) and (edge.v, edge.port_v) == (b, 0)
    assert m.node(n1).ports[p1["out"]] == e5b and m.node(n1).ports[p1["next"]] == e12
    assert m.node(n1).departures_rad == frame  # ports keep meaning what they meant
    assert m.node(n1).ambiguous_with == frozenset({n2})
    assert m.node(n2).ambiguous_with == frozenset({n1})  # 5's old partners now point at 1
    assert m.version == before + 1 and m.changes[-1].op == "merge"
    assert m.changes[-1].data["nodes"] == [[n5, n1, k]]


def test_merge_makes_an_edge_between_the_two_a_loop():
    m = TopoMap()
    a = m.add_meet(1.0, [0.0, 2.0, 4.0], pose=(0, 0))
    c = m.add_meet(1.0, [1.0, 3.0, 5.0], pose=(0.5, 0))
    e = m.connect(a, 0, c, 1, 6.0)  # round an obstacle and back: the same place
    m.merge(a, c, 1)  # c's port 1 is a's port 2
    assert m.edge(e).u == m.edge(e).v == a
    assert {m.edge(e).port_u, m.edge(e).port_v} == {0, 2}
    assert m.unexplored() == [(a, 1)]
    with pytest.raises(MapError, match="same port"):
        m2 = TopoMap()
        a = m2.add_meet(1.0, [0.0, 2.0, 4.0], pose=(0, 0))
        c = m2.add_meet(1.0, [1.0, 3.0, 5.0], pose=(0.5, 0))
        m2.connect(a, 0, c, 1, 6.0)
        m2.merge(a, c, 2)  # would put both ends of the edge on a's port 0


def test_fig12_second_lap_merge_follows_the_topology():
    """5 is 1 settles 6 is 2 and 7 is 3: their edges leave by the same ports."""
    m = TopoMap()
    nodes = first_lap(m)
    (n4, p4) = nodes[3]
    n5, p5 = corner(m, 0, drift=0.2, clearance=1.02)
    m.connect(n4, p4["next"], n5, p5["prev"], 4.05)
    n6, p6 = corner(m, 1, drift=0.25, clearance=0.98)
    m.connect(n5, p5["next"], n6, p6["prev"], 4.02)
    n7, p7 = corner(m, 2, drift=0.3)
    m.connect(n6, p6["next"], n7, p7["prev"], 4.12)
    (k,) = m.signature_rotations(n5, 1, 0.1, 0.1)
    plan = m.plan_merge(1, n5, k)
    assert m.has_node(n5)  # planning changes nothing
    assert set(plan.nodes) == {n5, n6, n7}
    assert [plan.nodes[n][0] for n in (n5, n6, n7)] == [1, 2, 3]
    assert plan.edges == {5: 1, 6: 2}
    m.merge(1, n5, k)
    assert [n.id for n in m.nodes()] == [1, 2, 3, 4]
    assert m.edge(1).lengths_m == (4.0, 4.02) and m.edge(2).lengths_m == (4.1, 4.12)
    assert len(m.edges()) == 4 and len(nx.cycle_basis(nx.Graph(m.graph))) == 1
    assert m.unexplored() == [(n, p["out"]) for n, p in nodes]
    closing = m.edge(4)
    assert {(closing.u, closing.port_u), (closing.v, closing.port_v)} == {
        (4, p4["next"]),
        (1, nodes[0][1]["prev"]),
    }
    data = m.to_dict()
    assert TopoMap.from_dict(data).to_dict() == data  # the merged map is consistent


def test_an_inconsistent_merge_raises_and_changes_nothing():
    m = TopoMap()
    n1, p1 = corner(m, 0)
    n2, p2 = corner(m, 1)
    m.connect(n1, p1["next"], n2, p2["prev"], 4.0)
    n5, p5 = corner(m, 0, drift=0.3)
    b = m.add_boundary(0.4, pose=(0, -3))
    m.connect(n5, p5["next"], b, 0, 1.0)  # where 1 leads to meet point 2, 5 hits a dead end
    k = (p1["next"] - p5["next"]) % 3
    snapshot, version = m.to_dict(), m.version
    with pytest.raises(MapError, match=r"boundary .* the same place as meet|meet .* boundary"):
        m.merge(n1, n5, k)
    assert m.to_dict() == snapshot and m.version == version
    with pytest.raises(MapError, match=r"boundary 4 \(degree 1\) the same place as meet 1"):
        m.merge(n1, b, 0)
    with pytest.raises(MapError, match="rotation must be an integer"):
        m.merge(n1, n5, 1.0)
    with pytest.raises(MapError, match="itself"):
        m.merge(n1, n1, 0)


def test_a_merge_that_needs_two_rotations_raises():
    # Two parallel edges between 1 and 2, and a revisit of 2 whose edges to 1 are swapped.
    m = TopoMap()
    a = m.add_meet(1.0, [0.0, 2.0, 4.0], pose=(0, 0))
    b = m.add_meet(1.0, [0.0, 2.0, 4.0], pose=(3, 0))
    m.connect(a, 0, b, 1, 3.0)
    m.connect(a, 1, b, 0, 3.5)
    c = m.add_meet(1.0, [0.0, 2.0, 4.0], pose=(3, 0))
    m.connect(a, 2, c, 0, 3.0)
    with pytest.raises(MapError):
        m.merge(b, c, 0)  # c's port 0 = b's port 0, whose edge leaves a by port 1, not 2


# -- planning -------------------------------------------------------------------------------


def diamond() -> tuple[TopoMap, dict[str, int]]:
    """S to D two ways: through A (2 + 2 m) and through B (1 + 1.5 m)."""
    m = TopoMap()
    ids = {
        k: m.add_meet(1.0, [0.0, 2.0, 4.0], pose=xy)
        for k, xy in {"S": (0, 0), "A": (2, 1), "B": (1, -1), "D": (3, 0)}.items()
    }
    m.connect(ids["S"], 0, ids["A"], 0, 2.0)
    m.connect(ids["A"], 1, ids["D"], 0, 2.0)
    m.connect(ids["S"], 1, ids["B"], 0, 1.0)
    m.connect(ids["B"], 1, ids["D"], 1, 1.5)
    return m, ids


def test_shortest_path_takes_the_shorter_route():
    m, ids = diamond()
    path = m.shortest_path(ids["S"], ids["D"])
    assert path == [Step(ids["S"], 1, 3, ids["B"], 0), Step(ids["B"], 1, 4, ids["D"], 1)]
    # Retrace measurements make the B route long: the median moves, so does the plan.
    for _ in range(2):
        m.add_measurement(4, 5.0)
    assert [s.next_node for s in m.shortest_path(ids["S"], ids["D"])] == [ids["A"], ids["D"]]
    assert m.shortest_path(ids["D"], ids["D"]) == []


def test_shortest_path_picks_the_shorter_of_two_parallel_edges():
    m = TopoMap()
    a = m.add_meet(1.0, [0.0, 2.0, 4.0], pose=(0, 0))
    b = m.add_meet(1.0, [0.0, 2.0, 4.0], pose=(3, 0))
    m.connect(a, 0, b, 1, 5.0)
    short = m.connect(a, 2, b, 0, 3.0)
    assert m.shortest_path(b, a) == [Step(b, 0, short, a, 2)]
    c = m.add_meet(1.0, [0.0, 2.0, 4.0], pose=(9, 9))
    with pytest.raises(MapError, match=f"no path from node {a} to node {c}"):
        m.shortest_path(a, c)


def test_an_edge_made_longer_for_planning_is_gone_round():
    m, ids = diamond()
    # Edge 3 (S-B, 1 m) counted 20 m longer: through A (4 m) beats through B (22.5 m).
    path = m.shortest_path(ids["S"], ids["D"], {3: 20.0})
    assert [s.edge for s in path] == [1, 2]
    assert m.distances(ids["S"], {3: 20.0})[ids["D"]] == pytest.approx(4.0)
    assert m.distances(ids["S"])[ids["D"]] == pytest.approx(2.5)
    # Of two parallel edges, the shorter made longer is the other's to take.
    a, b = ids["S"], ids["B"]
    long = m.connect(a, 2, b, 2, 3.0)
    assert m.shortest_path(a, b, {3: 20.0}) == [Step(a, 2, long, b, 2)]
    assert m.shortest_path(a, b) == [Step(a, 1, 3, b, 0)]


def test_nearest_unexplored():
    m = TopoMap()
    s = m.add_boundary(0.4, pose=(0, 0))
    a = m.add_meet(1.0, [0.0, 2.0, 4.0], pose=(1, 0))
    b = m.add_meet(1.0, [0.0, 2.0, 4.0], pose=(3, 0))
    c = m.add_meet(1.0, [0.0, 2.0, 4.0], pose=(9, 0))
    m.connect(s, 0, a, 0, 1.0)
    m.connect(a, 1, b, 0, 2.0)
    m.connect(a, 2, b, 1, 5.0)
    m.connect(b, 2, c, 0, 6.0)
    f = m.nearest_unexplored(s)
    assert f is not None
    # b is full; c (1 + 2 + 6 m away) has two unexplored departures: the first is chosen.
    assert (f.node, f.port, f.length_m) == (c, 1, 9.0)
    assert [st.edge for st in f.path] == [1, 2, 4] and f.path[-1].next_node == c
    here = m.nearest_unexplored(c)
    assert here is not None and (here.node, here.path, here.length_m) == (c, [], 0.0)
    m.connect(c, 1, c, 2, 7.0)  # close the last departures with a loop
    assert m.nearest_unexplored(s) is None and m.unexplored() == []


# -- the reduced GVG ----------------------------------------------------------------------------


def test_reduced_joins_edges_through_weak_meet_points():
    m = TopoMap()
    a = m.add_meet(1.0, [0.0, 2.0, 4.0], pose=(0, 0))
    w = m.add_meet(0.8, [0.0, 1.5, 3.1], pose=(2, 0))  # beside a shallow indent
    c = m.add_meet(1.0, [0.0, 2.0, 4.0], pose=(4, 0))
    ind = m.add_boundary(0.3, pose=(2, 1))
    m.connect(a, 0, w, 2, 2.0)
    m.connect(w, 0, c, 1, 2.5)
    m.connect(w, 1, ind, 0, 0.7)
    m.set_ambiguous(a, [w])
    r = m.reduced()
    assert [n.id for n in r.nodes()] == [a, c]
    (e,) = r.edges()
    assert (e.u, e.port_u, e.v, e.port_v, e.lengths_m) == (a, 0, c, 1, (4.5,))
    assert r.node(a).ports[0] == e.id and r.node(a).ambiguous_with == frozenset()
    assert r.version == 0 and r.changes == ()
    assert len(m.nodes()) == 4 and m.node(a).ambiguous_with == {w}  # the map itself is untouched
    assert TopoMap.from_dict(r.to_dict()).to_dict() == r.to_dict()


def test_reduced_keeps_real_junctions_and_loose_ends():
    m = TopoMap()
    j = m.add_meet(1.0, [0.0, 1.5, 3.0, 4.5], pose=(0, 0))
    ind = m.add_boundary(0.3, pose=(1, 0))
    a = m.add_meet(1.0, [0.0, 2.0, 4.0], pose=(0, 3))
    m.connect(j, 0, ind, 0, 0.5)
    m.connect(j, 1, a, 0, 3.0)
    w = m.add_meet(1.0, [0.0, 2.0, 4.0], pose=(0, -3))
    m.connect(j, 3, w, 0, 3.0)
    m.connect(w, 1, m.add_boundary(0.3, pose=(1, -3)), 0, 0.5)  # w's port 2 unexplored
    r = m.reduced()
    # j had four edges, one a dead end: it is still a junction of three, its spur gone.
    assert r.node(j).departures_rad == (1.5, 3.0, 4.5)
    assert r.node(j).ports == (2, None, None)
    assert r.edge(2).v == a and r.edge(2).port_u == 0
    # w, on the way to the unexplored, vanished: j's edge now runs into the unknown.
    assert not r.has_node(w) and (j, 2) in r.unexplored()


def test_reduced_fig12_ring_of_weak_points_keeps_one_node_on_a_loop():
    m = TopoMap()
    nodes = first_lap(m)
    (n1, p1), (n4, p4) = nodes[0], nodes[3]
    m.connect(n4, p4["next"], n1, p1["prev"], 4.0)
    for i, (n, p) in enumerate(nodes):
        m.connect(n, p["out"], m.add_boundary(0.3, pose=(3 * RING[i][0], 3 * RING[i][1])), 0, 1.0)
    r = m.reduced()
    (node,) = r.nodes()
    (loop,) = r.edges()
    assert loop.u == loop.v == node.id and loop.length_m == pytest.approx(16.0)


# -- serialisation ------------------------------------------------------------------------------


@st.composite
def random_maps(draw) -> TopoMap:
    m = TopoMap()
    angle = st.floats(0.0, TAU, exclude_max=True, allow_subnormal=False)
    xy = st.tuples(st.floats(-50, 50), st.floats(-50, 50))
    for _ in range(draw(st.integers(1, 6))):
        truth = draw(st.none() | xy)
        if draw(st.booleans()):
            m.add_boundary(draw(st.floats(0, 3)), draw(xy), draw(angle), truth)
        else:
            deps = draw(st.lists(angle, min_size=1, max_size=4, unique=True))
            m.add_meet(draw(st.floats(0, 3)), sorted(deps), draw(xy), truth)
    for _ in range(draw(st.integers(0, 8))):
        free = m.unexplored()
        if len(free) < 2:
            break
        i, j = draw(
            st.lists(st.sampled_from(range(len(free))), min_size=2, max_size=2, unique=True)
        )
        m.connect(*free[i], *free[j], draw(st.floats(0, 100)))
    for e in m.edges():
        for x in draw(st.lists(st.floats(0, 100), max_size=3)):
            m.add_measurement(e.id, x)
    ids = [n.id for n in m.nodes()]
    m.set_ambiguous(ids[0], draw(st.lists(st.sampled_from(ids), max_size=3)))
    return m


@FUZZ
@given(m=random_maps())
def test_json_round_trip_is_exact(m):
    text = json.dumps(m.to_dict())
    back = TopoMap.from_dict(json.loads(text))
    assert back.nodes() == m.nodes() and back.edges() == m.edges()
    assert json.dumps(back.to_dict()) == text
    assert back.unexplored() == m.unexplored()
    # New ids never collide with the loaded ones.
    assert back.add_meet(1.0, [0.0], (0, 0)) == max(n.id for n in m.nodes()) + 1


def small_map_dict() -> dict:
    """Node 1 (meet) -- edge 1 -- node 2 (meet) -- edge 2 -- node 3 (boundary)."""
    m = TopoMap()
    a = m.add_meet(1.0, [0.0, 2.0, 4.0], pose=(0, 0), truth=(0.1, 0.0))
    b = m.add_meet(1.1, [1.0, 3.0, 5.0], pose=(3, 0))
    c = m.add_boundary(0.4, pose=(3, 2), departure_rad=4.7)
    m.connect(a, 0, b, 1, 3.0)
    m.add_measurement(1, 3.2)
    m.connect(b, 2, c, 0, 2.0)
    m.set_ambiguous(a, [b])
    return m.to_dict()


def _set(path, value):
    def mutate(d):
        target = d
        for key in path[:-1]:
            target = target[key]
        target[path[-1]] = value
        return d

    return mutate


def _del(path):
    def mutate(d):
        target = d
        for key in path[:-1]:
            target = target[key]
        del target[path[-1]]
        return d

    return mutate


MALFORMED = [
    ("not an object", lambda d: [d], "the map must be an object, not array"),
    ("format", _set(["format"], "tslam-world"), "'format' is 'tslam-world', expected 'tslam-map'"),
    ("version", _set(["version"], 2), "unsupported 'version' 2"),
    ("version bool", _set(["version"], True), "unsupported 'version' True"),
    ("no nodes", _del(["nodes"]), "missing key 'nodes'"),
    ("nodes type", _set(["nodes"], {}), "'nodes' must be an array, not object"),
    ("node type", _set(["nodes", 0], 5), "nodes[0] must be an object, not number"),
    ("node id bool", _set(["nodes", 0, "id"], True), "nodes[0]: 'id' must be an integer"),
    ("node key", _del(["nodes", 1, "kind"]), "node 2: missing key 'kind'"),
    ("kind", _set(["nodes", 1, "kind"], "door"), "node 2: 'kind' must be 'meet' or 'boundary'"),
    (
        "clearance type",
        _set(["nodes", 0, "clearance_m"], "1"),
        "node 1: 'clearance_m' must be a number, not string",
    ),
    ("clearance sign", _set(["nodes", 0, "clearance_m"], -1.0), "node 1: 'clearance_m' must be"),
    (
        "degree",
        _set(["nodes", 0, "degree"], 4),
        "node 1: 'departures_rad' has 3 angles for degree 4",
    ),
    ("boundary degree", _set(["nodes", 2, "degree"], 2), "node 3: 'degree' 2 is impossible"),
    (
        "order",
        _set(["nodes", 0, "departures_rad"], [4.0, 2.0, 0.0]),
        "node 1: 'departures_rad' must be strictly ascending",
    ),
    (
        "range",
        _set(["nodes", 0, "departures_rad", 2], 7.0),
        "node 1: 'departures_rad'[2] = 7.0 is outside",
    ),
    (
        "nan",
        _set(["nodes", 0, "departures_rad", 0], float("nan")),
        "node 1: 'departures_rad'[0] must be a finite",
    ),
    (
        "ports length",
        lambda d: d["nodes"][0]["ports"].append(None) or d,
        "node 1: 'ports' has 4 entries",
    ),
    (
        "port type",
        _set(["nodes", 0, "ports", 0], "1"),
        "node 1: 'ports'[0] must be an integer, not string",
    ),
    ("pose", _set(["nodes", 0, "pose"], [1.0]), "node 1: 'pose' must be a pair"),
    ("truth", _del(["nodes", 0, "truth", "y"]), "node 1: 'truth': missing key 'y'"),
    (
        "ambiguous unknown",
        _set(["nodes", 0, "ambiguous_with"], [9]),
        "node 1: 'ambiguous_with' names node 9",
    ),
    (
        "ambiguous self",
        _set(["nodes", 0, "ambiguous_with"], [1]),
        "node 1: 'ambiguous_with' names node 1",
    ),
    ("duplicate node", _set(["nodes", 1, "id"], 1), "node 1: duplicate id"),
    ("edges type", _set(["edges"], None), "'edges' must be an array, not null"),
    ("edge key", _del(["edges", 0, "u"]), "edge 1: missing key 'u'"),
    ("dangling", _set(["edges", 0, "v"], 99), "edge 1: 'v' is node 99, which is not in the map"),
    (
        "port range",
        _set(["edges", 0, "port_u"], 3),
        "edge 1: 'port_u' 3 is out of range for node 1 (degree 3)",
    ),
    (
        "port disagrees",
        _set(["edges", 0, "port_u"], 1),
        "edge 1: leaves node 1 by port 1, but that port of node 1 holds None",
    ),
    (
        "port names no edge",
        _set(["nodes", 0, "ports", 1], 42),
        "node 1: 'ports'[1] names edge 42, which is not in the map",
    ),
    (
        "port names other edge",
        _set(["nodes", 0, "ports", 1], 2),
        "node 1: 'ports'[1] names edge 2, which does not leave node 1 by port 1",
    ),
    (
        "same port twice",
        lambda d: _set(["edges", 0, "port_v"], 0)(_set(["edges", 0, "v"], 1)(d)),
        "edge 1: leaves and returns to node 1 by the same port 0",
    ),
    (
        "length median",
        _set(["edges", 0, "length_m"], 3.0),
        "edge 1: 'length_m' 3.0 is not the median",
    ),
    ("no lengths", _set(["edges", 0, "lengths_m"], []), "edge 1: 'lengths_m' is empty"),
    ("negative length", _set(["edges", 0, "lengths_m", 0], -1.0), "edge 1: 'lengths_m'[0] must be"),
    ("duplicate edge", _set(["edges", 1, "id"], 1), "edge 1: duplicate id"),
]


@pytest.mark.parametrize(
    ("mutate", "message"), [m[1:] for m in MALFORMED], ids=[m[0] for m in MALFORMED]
)
def test_malformed_maps_are_rejected_by_name(mutate, message):
    data = mutate(copy.deepcopy(small_map_dict()))
    with pytest.raises(MapFormatError) as info:
        TopoMap.from_dict(data)
    assert message in str(info.value)
    assert isinstance(info.value, ValueError)


def test_the_unmutated_small_map_loads():
    data = small_map_dict()
    assert TopoMap.from_dict(data).to_dict() == data
    assert "truth" not in data["nodes"][1]  # absent, not null, when unknown


json_values = st.recursive(
    st.none()
    | st.booleans()
    | st.integers(-5, 5)
    | st.floats(allow_nan=True)
    | st.text(max_size=3),
    lambda inner: (
        st.lists(inner, max_size=3) | st.dictionaries(st.text(max_size=3), inner, max_size=3)
    ),
    max_leaves=6,
)


def _paths(obj, prefix=()):
    yield prefix
    if isinstance(obj, dict):
        for k, v in obj.items():
            yield from _paths(v, (*prefix, k))
    elif isinstance(obj, list):
        for i, v in enumerate(obj):
            yield from _paths(v, (*prefix, i))


SMALL_PATHS = list(_paths(small_map_dict()))[1:]


@FUZZ
@given(path=st.sampled_from(SMALL_PATHS), value=json_values)
def test_fuzzed_fields_raise_only_map_format_error(path, value):
    data = _set(list(path), value)(copy.deepcopy(small_map_dict()))
    try:
        m = TopoMap.from_dict(data)
    except MapFormatError as exc:
        assert "\n" not in str(exc)
    else:
        assert TopoMap.from_dict(m.to_dict()).to_dict() == m.to_dict()


# -- files --------------------------------------------------------------------------------------


def test_save_and_load(tmp_path):
    m = TopoMap.from_dict(small_map_dict())
    path = tmp_path / "maps" / "lab.json"
    save_map(path, m)
    assert stat.S_IMODE(os.stat(path).st_mode) == 0o644
    assert load_map(path).to_dict() == m.to_dict()
    assert json.loads(path.read_text())["format"] == "tslam-map"


def test_load_problems_name_the_file(tmp_path):
    missing = tmp_path / "none.json"
    with pytest.raises(MapFormatError, match=rf"^{missing}: no such file$"):
        load_map(missing)
    bad = tmp_path / "bad.json"
    bad.write_text('{"format": "tslam-map",')
    with pytest.raises(MapFormatError, match=rf"^{bad}: not JSON: .* line 1 column"):
        load_map(bad)
    wrong = tmp_path / "wrong.json"
    wrong.write_text(json.dumps(_set(["edges", 0, "v"], 99)(small_map_dict())))
    with pytest.raises(MapFormatError, match=rf"^{wrong}: edge 1: 'v' is node 99"):
        load_map(wrong)


def test_a_failed_save_leaves_the_old_file_and_no_debris(tmp_path, monkeypatch):
    path = tmp_path / "map.json"
    save_map(path, TopoMap.from_dict(small_map_dict()))
    old = path.read_text()

    def disk_full(fd):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr("tslam.programs.output.os.fsync", disk_full)
    with pytest.raises(UserError, match="No space left"):
        save_map(path, TopoMap())
    assert path.read_text() == old
    assert sorted(p.name for p in tmp_path.iterdir()) == ["map.json"]


# -- pictures -----------------------------------------------------------------------------------


def by_class(root: ET.Element, cls: str) -> list[ET.Element]:
    return [el for el in root.iter() if el.get("class") == cls]


def picture_map() -> TopoMap:
    m = TopoMap()
    nodes = first_lap(m)
    n1, p1 = nodes[0]
    m.connect(n1, p1["out"], m.add_boundary(0.3, pose=(-3, -3), truth=(-3.1, -2.9)), 0, 1.4)
    m.connect(2, nodes[1][1]["out"], 3, nodes[2][1]["out"], 6.0)  # a second edge 2-3
    m.set_ambiguous(3, [4])
    return m


@pytest.mark.parametrize("layout", ["odometry", "topological"])
def test_svg_has_one_marker_per_node(layout):
    m = picture_map()
    root = ET.fromstring(render_map_svg(m, layout=layout, show_truth=True))
    assert len(by_class(root, "map-meet")) == 4
    assert len(by_class(root, "map-boundary")) == 1
    assert sorted(int(t.text) for t in by_class(root, "map-label")) == [1, 2, 3, 4, 5]
    assert len(by_class(root, "map-edge")) == len(m.edges())
    assert len(by_class(root, "map-unexplored")) == len(m.unexplored()) == 3
    assert len(by_class(root, "map-ambiguous")) == 2
    assert len(by_class(root, "map-truth")) == (5 if layout == "odometry" else 0)


def test_topological_layout_reads_in_metres():
    m = picture_map()
    root = ET.fromstring(render_map_svg(m, layout="topological", px_per_m=10.0))
    pts = {
        int(lbl.text): (float(c.get("cx")), float(c.get("cy")))
        for c, lbl in zip(by_class(root, "map-meet"), by_class(root, "map-label"), strict=False)
    }
    # Kamada-Kawai cannot honour every length, but a 4 m edge is drawn a few metres long.
    assert 2.0 < math.dist(pts[1], pts[2]) / 10.0 < 6.0


def test_svg_background_is_drawn_first_and_files_are_shared(tmp_path):
    m = picture_map()
    seen = []

    def background(canvas):
        seen.append(canvas.bounds)
        canvas.rect(-10, -10, 20, 20, fill="#eeeeee", class_="bg")

    path = tmp_path / "map.svg"
    save_map_svg(path, m, background=background, bounds=(-10.0, -10.0, 10.0, 10.0))
    assert seen == [(-10.0, -10.0, 10.0, 10.0)]
    root = ET.fromstring(path.read_text())
    classes = [el.get("class") for el in root.iter() if el.get("class")]
    assert classes.index("bg") < classes.index("topomap")
    assert stat.S_IMODE(os.stat(path).st_mode) == 0o644


def test_svg_of_an_empty_map_and_a_bad_layout():
    root = ET.fromstring(render_map_svg(TopoMap(), layout="topological"))
    assert by_class(root, "map-meet") == []
    with pytest.raises(ValueError, match="layout must be one of"):
        render_map_svg(TopoMap(), layout="geographic")


LIKE = Likeness(clearance_m=0.15, angle_rad=math.radians(25.0), length_abs_m=0.25, length_rel=0.08)


def two_sightings(length: float, clearance: float = 1.0):
    """Ring corners 0 and 1 joined by a 4 m edge, then seen again with the heading 0.3 rad
    off: corner 1 with ``clearance`` and the edge ``length`` long. Returns the map, the four
    (node, ports) and the rotation that makes the second sighting of corner 0 the first."""
    m = TopoMap()
    (n1, p1), (n2, p2) = corner(m, 0), corner(m, 1)
    m.connect(n1, p1["next"], n2, p2["prev"], 4.0)
    (n5, p5), (n6, p6) = corner(m, 0, drift=0.3), corner(m, 1, drift=0.3, clearance=clearance)
    m.connect(n5, p5["next"], n6, p6["prev"], length)
    return m, (n1, p1), (n2, p2), (n5, p5), (n6, p6), (p1["next"] - p5["next"]) % 3


def test_a_merge_that_zips_edges_of_other_lengths_raises_when_told_to_compare():
    """Kind and degree alone let a proven pair carry the merge on, edge by edge, to places
    that only have the degree in common; compared as a prediction is, the edges differ."""
    m, (n1, _), (n2, p2), (n5, _), (n6, p6), k = two_sightings(2.5)  # 1.5 m short
    snapshot = m.to_dict()
    with pytest.raises(MapError, match=r"edge \d+ \(2\.50 m\) edge \d+ \(4\.00 m\)"):
        m.merge(n1, n5, k, LIKE)
    assert m.to_dict() == snapshot
    assert m.merge(n1, n5, k).nodes == {n5: (n1, k), n6: (n2, (p2["prev"] - p6["prev"]) % 3)}


def test_a_merge_that_zips_onto_a_node_that_looks_otherwise_raises_when_told_to_compare():
    m, (n1, _), (n2, _), (n5, _), (n6, _), k = two_sightings(4.0, clearance=1.6)  # 0.6 m wider
    with pytest.raises(MapError, match=rf"node {n6} the same place as node {n2}, which looks"):
        m.merge(n1, n5, k, LIKE)
    m2, (a, _), _, (c, _), (d, _), k2 = two_sightings(4.2, clearance=1.05)
    assert set(m2.merge(a, c, k2, LIKE).nodes) == {c, d}


def dead_ends(deep_length: float, deep_clearance: float):
    """``two_sightings`` with a dead end off each sighting of corner 0: first reached 0.36 m
    out at clearance 0.44 m, then ``deep_length`` out at ``deep_clearance``."""
    m, (n1, p1), _, (n5, p5), _, k = two_sightings(4.0)
    b1 = m.add_boundary(0.44, pose=(-2.0, 0.0))
    b5 = m.add_boundary(deep_clearance, pose=(-2.0, 0.3))
    m.connect(n1, p1["prev"], b1, 0, 0.36)
    m.connect(n5, p5["prev"], b5, 0, deep_length)
    return m, n1, n5, k


def test_a_dead_end_reached_deeper_nearer_the_walls_is_the_same_edge():
    """fig14 seed 1 mapped one dead end 0.36 m from its junction at clearance 0.44 m and
    then 0.67 m at 0.29 m: the boundary rule stopped the robot where the gap pinched. The
    prediction allows for that (``Boundaries._dead_end_tol``), so the merge must as well,
    or the proven loop is never closed and the lab is mapped again and again."""
    deeper = replace(LIKE, dead_end_depth=1.5)
    m, n1, n5, k = dead_ends(0.67, 0.29)
    with pytest.raises(EdgeConflictError):
        m.plan_merge(n1, n5, k, LIKE)
    assert n5 in m.plan_merge(n1, n5, k, deeper).nodes
    # Deeper in by 0.39 m with 2 cm of clearance to show for it is another edge.
    m2, a, c, k2 = dead_ends(0.75, 0.42)
    with pytest.raises(EdgeConflictError):
        m2.plan_merge(a, c, k2, deeper)


def test_a_merge_zips_onto_a_dead_end_whatever_clearance_it_was_read_with():
    """A boundary point's clearance is where the boundary rule stopped the robot (0.45 m with
    the corner ahead, nearer where the gap pinches): fig1's corner read 0.44 m and 0.29 m kept a
    proven placement from merging. A meet point's clearance still counts."""
    m, (n1, p1), _, (n5, p5), _, k = two_sightings(4.0)
    b1 = m.add_boundary(0.44, pose=(-2.0, 0.0))
    b5 = m.add_boundary(0.25, pose=(-2.0, 0.3))
    m.connect(n1, p1["prev"], b1, 0, 1.5)
    m.connect(n5, p5["prev"], b5, 0, 1.5)
    assert m.plan_merge(n1, n5, k, LIKE).nodes[b5] == (b1, 0)
    assert rotations(m.signature(b5), m.signature(b1), 0.15, 0.44) == [0]
    m2, (a, _), _, (c, _), _, k2 = two_sightings(4.0, clearance=1.6)
    with pytest.raises(MapError, match="which looks otherwise"):
        m2.plan_merge(a, c, k2, LIKE)

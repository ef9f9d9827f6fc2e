"""The arbiter and localization on true GVGs walked without a simulator (tests/graph_walk.py):
the decisions alone, with heading drift of 3 degrees per edge and 3 % noise on clearances and
lengths."""

from __future__ import annotations

import json
import math

import pytest

from hal.interfaces import NOMAD200_LIMITS
from sim_backend.ground_truth import compute_gvg
from sim_backend.world_files import load_world
from tests.graph_walk import TrueGraph, from_ground_truth, passed_once, walk
from tslam.core.explorer import Explorer, ExplorerParams
from tslam.core.localize import Hypothesis
from tslam.core.topomap import TopoMap
from tslam.core.tracer import MeetPointReached


def false_merges(ex: Explorer) -> int:
    return sum(
        1
        for m in ex.merges
        for _, _, td, tr in m.pairs
        if td and tr and math.hypot(td[0] - tr[0], td[1] - tr[1]) > 0.5
    )


@pytest.mark.parametrize("world", ["fig1", "fig13", "fig14", "fig16"])
def test_exploration_finds_every_node_and_edge_once(world):
    gvg = compute_gvg(load_world(world))
    graph = from_ground_truth(gvg)
    ex = Explorer(NOMAD200_LIMITS)
    start = next(n for n, v in graph.nodes.items() if v[0] == "meet")
    walk(graph, ex, start, max_arrivals=400, noise=0.03, seed=2)
    assert ex.done and not ex.map.unexplored()
    assert false_merges(ex) == 0
    assert sum(n.kind == "meet" for n in ex.map.nodes()) == len(gvg.meet_points)
    assert len(ex.map.edges()) == len(gvg.edges)


def triangle() -> TrueGraph:
    """fig12's shape: three look-alike junctions round a block, each with a dead end."""
    g = TrueGraph()
    g.meet("A", 1.4, 6.6, [135, 270, -45])
    g.meet("B", 6.4, 1.5, [-45, 180, 135])
    g.meet("C", 1.4, 1.5, [225, 90, 0])
    for name, x, y in (("a", 0.5, 7.5), ("b", 7.5, 0.5), ("c", 0.5, 0.5)):
        g.boundary(name, x, y)
    g.edge("A", 135, "a", 0, 1.3)
    g.edge("B", -45, "b", 0, 1.5)
    g.edge("C", 225, "c", 0, 1.5)
    g.edge("A", -45, "B", 135, 11.0)
    g.edge("B", 180, "C", 0, 5.2)
    g.edge("C", 90, "A", 270, 5.4)
    return g


def test_the_loop_closes_by_topology_with_proof_not_on_first_sight():
    ex = Explorer(NOMAD200_LIMITS)
    visited = walk(triangle(), ex, "A", drift_deg_per_edge=10.0)
    assert ex.done and len(ex.merges) == 1 and false_merges(ex) == 0
    assert [n.kind for n in ex.map.nodes()].count("meet") == 3
    # The closing merge came after the robot had gone round the loop and on: at least two
    # predicted edges confirmed, as in the paper's Fig. 12.
    assert visited.count("A") >= 2
    merged = {d for d, _, _, _ in ex.merges[0].pairs}
    assert len(merged) >= 2



@pytest.mark.parametrize("cut", [2, 3])
def test_a_restart_localizes_against_the_stored_map_and_finishes_it(cut):
    first = Explorer(NOMAD200_LIMITS)
    walk(triangle(), first, "A", max_arrivals=cut)
    stored = TopoMap.from_dict(json.loads(json.dumps(first.map.to_dict())))
    before = {n.id for n in stored.nodes()}
    assert not first.done and stored.unexplored()
    # The robot is back where it first started and reaches A off the graph: the stored map
    # is the prior, so A's one look-alike, confirmed by the edge it then traces, is A.
    second = Explorer(NOMAD200_LIMITS, tmap=stored)
    walk(triangle(), second, "A", drift_deg_per_edge=10.0)
    assert second.done and false_merges(second) == 0
    assert second.merges, "the restart never localized against the stored map"
    assert [n.kind for n in second.map.nodes()].count("meet") == 3
    assert before <= {n.id for n in second.map.nodes()}


def test_without_a_stored_map_one_unproven_look_alike_is_not_merged():
    ex = Explorer(NOMAD200_LIMITS)
    walk(triangle(), ex, "A", max_arrivals=2)
    assert not ex._resuming
    deps = tuple(sorted(math.radians(b) % math.tau for b in (135, 270, -45)))
    rel = tuple((d - deps[0]) % math.tau for d in deps)
    ex._lost(MeetPointReached(0.0, 9.0, 9.0, 1.0, 3, deps, None, rel, None), "test")
    (h,) = ex.hyps.live
    h.confirmed = 1  # one predicted meet point found ...
    (old, _), = h.mapping.values()
    assert ex._resolve(old) == {} and not ex.merges  # ... at a node that tests nothing more
    assert ex.hyps.live == [h]  # kept open for a later edge to test
    assert h.lost_start and not h.resumed


def crossroads() -> TrueGraph:
    """A four-way junction J between two three-way ones, with dead ends all round."""
    g = TrueGraph()
    g.meet("A", 0.0, 4.0, [30, 150, 270])
    g.meet("J", 0.0, 0.0, [0, 90, 180, 270])
    g.meet("C", 0.0, -4.0, [90, 210, 330])
    for name, x, y in (("a1", 1.3, 4.7), ("a2", -1.3, 4.7), ("j1", 1.5, 0.0),
                       ("j2", -1.5, 0.0), ("c1", -1.3, -4.7), ("c2", 1.3, -4.7)):  # fmt: skip
        g.boundary(name, x, y)
    g.edge("A", 30, "a1", 0, 1.5)
    g.edge("A", 150, "a2", 0, 1.5)
    g.edge("A", 270, "J", 90, 4.0)
    g.edge("J", 0, "j1", 0, 1.5)
    g.edge("J", 180, "j2", 0, 1.5)
    g.edge("J", 270, "C", 90, 4.0)
    g.edge("C", 210, "c1", 0, 1.5)
    g.edge("C", 330, "c2", 0, 1.5)
    return g


def junction_read_as_two(node: str, came_by: int | None, visits: int) -> list[float] | None:
    """After its first visit J reads as three-way: the two edges on the side away from the
    one the robot came by show as one between them (a close pair homed on from one side)."""
    if node != "J" or visits == 0 or came_by is None:
        return None
    edges = [0.0, 90.0, 180.0, 270.0]
    far = [(came_by + 1) % 4, (came_by + 2) % 4]
    a, b = edges[far[0]], edges[far[1]]
    between = (a + ((b - a) % 360.0) / 2.0) % 360.0
    return sorted([e for i, e in enumerate(edges) if i not in far] + [between])


def test_a_junction_read_with_an_edge_fewer_at_the_end_of_a_known_edge_is_still_its_node():
    ex = Explorer(NOMAD200_LIMITS)
    visited = walk(crossroads(), ex, "A", drift_deg_per_edge=5.0, misread=junction_read_as_two)
    assert visited.count("J") >= 3  # it came back to J by known edges, misread each time
    assert not [n.text for n in ex.notes if n.text.startswith("lost (expected")]
    assert any("read with degree 3, not 4" in n.text for n in ex.notes)
    assert ex.done and not ex.map.unexplored()
    assert [n.kind for n in ex.map.nodes()].count("meet") == 3
    assert len(ex.map.edges()) == 8
    assert false_merges(ex) == 0


def test_a_look_alike_whose_edges_do_not_all_match_the_map_is_not_merged():
    # fig15's wings mirror each other. Walked from m4 with 5 degrees of heading drift per
    # edge, a wrong look-alike gathered its confirmations one prediction at a time while an
    # edge between two of its nodes, traced before both were mapped, disagreed with the map:
    # merged on the confirmations, 8 false merges followed. Placed as a whole it does not fit.
    gvg = compute_gvg(load_world("fig15"))
    graph = from_ground_truth(gvg)
    ex = Explorer(NOMAD200_LIMITS)
    starts = [n for n, v in graph.nodes.items() if v[0] == "meet"]
    walk(graph, ex, starts[1], max_arrivals=400, noise=0.03, seed=1, drift_deg_per_edge=5.0)
    assert false_merges(ex) == 0
    assert sum(n.kind == "meet" for n in ex.map.nodes()) >= len(gvg.meet_points)


def test_a_fragment_left_out_of_reach_by_losing_the_way_is_placed_and_the_map_finished():
    # Lost at arrival 20 while the fragment begun at arrival 13 was still being tested, and
    # again at 26: the fragment (five nodes) is left unattached, with one departure no path
    # leads to. Before, the first loss recorded its nodes as ambiguous with their look-alikes
    # (no move had been found that separates them: there was no move to make), and the map
    # was never complete: "1 departure(s) unexplored in fragments the robot has not placed
    # itself in". It fits one place only, so it is merged there, and exploration ends.
    gvg = compute_gvg(load_world("fig13"))
    graph = from_ground_truth(gvg)
    start = next(n for n, v in graph.nodes.items() if v[0] == "meet")
    runs = {}
    for place in (True, False):
        ex = Explorer(NOMAD200_LIMITS, params=ExplorerParams(place_orphans=place))
        walk(graph, ex, start, max_arrivals=200, noise=0.03, seed=2, lost_at=[20, 26])
        runs[place] = ex
        assert not [n.text for n in ex.notes if "ambiguous" in n.text]
        assert false_merges(ex) == 0
    ex = runs[True]
    assert any(n.text.endswith("out of reach, fit one place only") for n in ex.notes)
    assert ex.done and not ex.map.unexplored()
    assert sum(n.kind == "meet" for n in ex.map.nodes()) == len(gvg.meet_points)
    # Without placing it, the piece keeps its departure and the map is never complete.
    assert runs[False].done and runs[False].map.unexplored()


def _copies(n: int, m: TopoMap | None = None) -> tuple[TopoMap, list[list[int]]]:
    """``n`` unconnected copies of one stretch of map (in ``m`` if given): three junctions
    in a row, 3 m and 4 m apart, each with a departure still to explore."""
    m = TopoMap() if m is None else m
    out = []
    for i in range(n):
        nodes = [m.add_meet(1.2, (0.0, 2.1, 4.2), (10.0 * i + x, 0.0)) for x in (0.0, 3.0, 7.0)]
        m.connect(nodes[0], 0, nodes[1], 1, 3.0)
        m.connect(nodes[1], 0, nodes[2], 1, 4.0)
        out.append(nodes)
    return m, out


@pytest.mark.parametrize("copies, merged", [(2, True), (3, False)])
def test_a_piece_out_of_reach_is_merged_only_where_it_fits_alone(copies, merged):
    m, pieces = _copies(copies)
    ex = Explorer(NOMAD200_LIMITS, tmap=m)
    before = len(m.nodes())
    # The robot stands in the first piece; the others no path reaches. With two pieces the
    # second fits the first only; with three each fits two places, and none is merged.
    assert bool(ex._place_orphans(pieces[0][0])) is merged
    assert len(m.nodes()) == (before - 3 if merged else before)
    assert bool(ex.merges) is merged


def _closed_piece_and_strays(drop: bool, closed: bool) -> tuple[Explorer, list[int], dict]:
    """The robot's piece of map (three junctions; with ``closed`` every departure traced to
    a dead end) and, out of its reach: a node with no edge, a junction and its dead end, a
    node a live hypothesis names, and two junctions unlike any in the robot's piece."""
    ex = Explorer(NOMAD200_LIMITS, params=ExplorerParams(drop_detached=drop))
    m, (piece,) = _copies(1, ex.map)  # built by this run: no stored map
    for n in piece[: 3 if closed else 2]:
        for p, e in enumerate(m.node(n).ports):
            if e is None:
                m.connect(n, p, m.add_boundary(0.4, (0.0, 0.0)), 0, 1.0)
    stray = {
        "bare": m.add_meet(1.2, (0.0, 2.1, 4.2), (3.1, 0.0)),
        "named": m.add_meet(1.2, (0.0, 2.1, 4.2), (3.2, 0.0)),
        "pair": m.add_meet(1.2, (0.0, 2.1, 4.2), (3.3, 0.0)),
        # Read with an edge more than any junction of the robot's piece: it may hold what
        # that piece lacks (fig16 seed 20: the corridor place with both dead ends).
        "fuller": m.add_meet(1.2, (0.0, 1.6, 3.1, 4.7), (3.4, 0.0)),
        # As many edges, but wider than anything in the robot's piece.
        "wider": m.add_meet(2.0, (0.0, 2.1, 4.2), (3.5, 0.0)),
    }
    m.connect(stray["pair"], 0, m.add_boundary(0.4, (3.3, 1.0)), 0, 1.0)
    ex.hyps.fragment.add(stray["named"])
    ex.hyps.live = [Hypothesis({stray["named"]: (piece[1], 0)})]
    return ex, piece, stray


@pytest.mark.parametrize("drop", [True, False])
def test_pieces_out_of_reach_go_once_the_robots_piece_is_finished(drop):
    """fig16 seeds 12, 25, 36, 40 and 44 finished with a junction first read at its weak point,
    unattached, its departures unexplored for good; fig1 seed 41 with a node whose only edge
    had gone past a junction. The GVG is connected: the robot's finished piece holds every
    place it has been, and the rest are copies."""
    ex, piece, stray = _closed_piece_and_strays(drop, closed=True)
    assert not [n for n in ex.map.unexplored() if n[0] in piece]
    before = len(ex.map.nodes())
    assert ex._place_orphans(piece[0]) == {} and not ex.merges
    gone = {k for k, n in stray.items() if not ex.map.has_node(n)}
    assert gone == ({"bare", "pair"} if drop else set())
    assert len(ex.map.nodes()) == before - (3 if drop else 0)  # the pair's dead end too
    assert ex.map.has_node(stray["fuller"]) and ex.map.has_node(stray["wider"])
    assert all(ex.map.has_node(n) for n in piece)


def test_pieces_out_of_reach_stay_while_the_robots_piece_has_departures_to_explore():
    ex, piece, stray = _closed_piece_and_strays(True, closed=False)
    ex._place_orphans(piece[0])
    assert all(ex.map.has_node(n) for n in stray.values())


def test_a_stored_map_out_of_reach_stays():
    m, (piece, stored) = _copies(2)
    ex = Explorer(NOMAD200_LIMITS, tmap=m)  # both pieces are an earlier run's
    for n in piece:
        for p, e in enumerate(m.node(n).ports):
            if e is None:
                m.connect(n, p, m.add_boundary(0.4, (0.0, 0.0)), 0, 1.0)
    ex._drop_detached(piece[0])
    assert all(m.has_node(n) for n in stored)


@pytest.mark.parametrize("junction", ["7", "11"])
def test_a_mirror_image_that_a_junction_passed_unhomed_leaves_is_refused_by_heading(junction):
    # fig15 walked with meet point 7 or 11 passed once without homing: the edge that went past
    # it refutes the right placement of what the robot maps next, and the mirror wing, half a
    # turn away, is then the only place it fits. Topology cannot refuse that merge; dead
    # reckoning's heading, good to a few degrees over the distance walked, does.
    # (Rival placements on untraced edges, tests/test_explorer_rivals.py, are left out.)
    gvg = compute_gvg(load_world("fig15"))
    graph = from_ground_truth(gvg)
    start = next(n for n, v in graph.nodes.items() if v[0] == "meet")
    merges = {}
    for read in (True, False):
        ex = Explorer(NOMAD200_LIMITS, params=ExplorerParams(open_rivals=False))
        walk(
            graph, ex, start, max_arrivals=300, noise=0.03, seed=1, drift_deg_per_edge=0.5,
            passed=passed_once(graph, junction),
            read_distance=read,
        )  # fmt: skip
        merges[read] = false_merges(ex)
        if read:
            assert any("turned further than dead reckoning drifts" in n.text for n in ex.notes)
    assert merges[True] == 0 and merges[False] > 0


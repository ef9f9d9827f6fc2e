"""A new node read with an edge more or fewer than the old place the hypotheses predict there
(a close pair read as one junction on one visit and as one of its points on the next) is read
as that place: the hypothesis lives on and tests it like any node; it gets its own reading
back if nothing places it any more, and a place merged from a reading with an edge more gains
that edge (``tslam/core/predicted_place.py``)."""

from __future__ import annotations

import math

from hal.interfaces import NOMAD200_LIMITS
from hal.types import Odometry
from tests.test_explorer_past import _add, meet
from tslam.core.explorer import Explorer, ExplorerParams
from tslam.core.localize import Hypothesis

A_DEPS = [0, 100, 230]  # A: its departure 0 deg leads east, 3.6 m to the pair
PLACE = [1, 73, 186, 295]  # the pair read as one junction: A's edge comes in at 186
POINT = [72, 188, 330]  # its west point alone: the east point's two edges seen as one


def _degrees(ex: Explorer, n: int) -> list[int]:
    return [round(math.degrees(b)) for b in ex.map.node(n).departures_rad]


def _lost_copy_of_a(
    mapped: list[int], params: ExplorerParams | None = None
) -> tuple[Explorer, int, int, int, Hypothesis]:
    """A mapped with its east edge to the pair (read as ``mapped``); node X is A again,
    mapped by a robot that lost its way and tested as A (two confirmations); the robot is
    leaving X east. Returns the explorer, A, the pair's node, X and the hypothesis."""
    ex = Explorer(NOMAD200_LIMITS, params=params)
    a, pair = _add(ex, 1.0, A_DEPS, 0.0), _add(ex, 1.5, mapped, 3.6)
    west = min(mapped, key=lambda b: abs(b - 180))  # the pair's way west, to A
    ex.map.connect(a, 0, pair, sorted(mapped).index(west), 3.6)
    x = _add(ex, 1.0, A_DEPS, 20.0)
    h = Hypothesis({x: (a, 0)}, confirmed=2)
    ex.hyps.live, ex.hyps.fragment = [h], {x}
    ex.leaving = (x, 0)
    return ex, a, pair, x, h


def test_the_pair_read_at_one_point_is_read_as_the_place_predicted():
    ex, _, pair, _, h = _lost_copy_of_a(PLACE)
    node, pm = ex._arrive(meet(23.6, 0.0, POINT, 188, 3.6, 1.5))
    assert ex.hyps.live == [h]
    assert node != pair and h.mapping[node][0] == pair
    assert ex.map.node(node).degree == 4 and ex.map.node(node).clearance_m == 1.5
    # Port k of the new node is port (k + rotation) of the place, and the robot came in by
    # the place's west port.
    k = h.mapping[node][1]
    assert (pm.arrival + k) % 4 == PLACE.index(186)
    # The place's two east edges, seen as one departure, share it in the port map.
    east = [p for p in range(4) if (p + k) % 4 in (PLACE.index(1), PLACE.index(295))]
    assert [pm.index[p] for p in east] == [POINT.index(330)] * 2
    assert h.confirmed == 2  # a reading taken as the predicted place is no evidence for it
    assert any("which it is predicted to be" in n.text for n in ex.notes)


def test_without_it_the_hypothesis_is_refuted():
    ex, _, _, _, h = _lost_copy_of_a(PLACE, ExplorerParams(predicted_place=False))
    node, _ = ex._arrive(meet(23.6, 0.0, POINT, 188, 3.6, 1.5))
    assert h not in ex.hyps.live and ex.map.node(node).degree == 3


def test_a_reading_that_fits_no_prediction_is_left_as_read():
    # 60 degrees off the place's edges, and the edge 1.5 m too long: no place predicted.
    ex, _, _, _, h = _lost_copy_of_a(PLACE)
    node, _ = ex._arrive(meet(23.6, 0.0, [40, 188, 300], 188, 5.1, 1.5))
    assert h not in ex.hyps.live and _degrees(ex, node) == [40, 188, 300]


def test_a_node_no_hypothesis_places_gets_its_own_reading_back():
    ex, _, _, _, _ = _lost_copy_of_a(PLACE)
    node, _ = ex._arrive(meet(23.6, 0.0, POINT, 188, 3.6, 1.5))
    ex.hyps.live = []
    ex._own_readings_back(here=-1)
    assert _degrees(ex, node) == POINT and ex.map.node(node).clearance_m == 1.5
    # The edge it was reached by is on the reading's own arrival departure.
    (e,) = [e for e in ex.map.edges() if node in (e.u, e.v)]
    assert ex.map.node(node).ports[POINT.index(188)] == e.id
    assert any("read as it was" in n.text for n in ex.notes)


def test_a_place_merged_from_a_reading_with_an_edge_more_gains_that_edge():
    # The pair mapped from its west point alone; read from the east point with four edges.
    ex, a, pair, x, h = _lost_copy_of_a(POINT)
    node, _ = ex._arrive(meet(23.6, 0.0, PLACE, 186, 3.6, 1.5))
    assert h.mapping[node][0] == pair and ex.map.node(node).degree == 3
    ex._merge(h)
    assert not ex.map.has_node(x) and not ex.map.has_node(node)
    grown = ex.map.node(pair)
    assert grown.degree == 4 and sum(p is None for p in grown.ports) == 3
    (e,) = [e for e in ex.map.edges() if {e.u, e.v} == {a, pair}]
    assert grown.ports[PLACE.index(186)] == e.id
    assert any(f"node {pair} read again as its place, with 4 edges" in n.text for n in ex.notes)


def _new_edge_to_the_pair(params: ExplorerParams | None = None) -> tuple[Explorer, int, int]:
    """The pair mapped from its west point alone (its way west explored); the robot leaves
    another junction by an unexplored departure and homes onto the pair's east point, read
    with all four edges, coming in by the edge the map has unexplored at the west point
    (fig14 seed 1: the lab door's pair, reached from the north)."""
    ex = Explorer(NOMAD200_LIMITS, params=params)
    pair = _add(ex, 1.5, [72, 188, 340], 0.0)
    ex.map.connect(pair, 1, ex.map.add_boundary(0.4, (-1.5, 0.0)), 0, 1.5)
    f = _add(ex, 1.0, [0, 120, 240], 10.0)
    ex.leaving = (f, 1)
    # Read 30 m of driving ago: dead reckoning's heading tells the reading's one turn that
    # fits from the other (93 degrees).
    ex.born[pair] = 0.0
    ex._odo = Odometry(0.3, 0.1, 0.0, 0.0, 0.0, 30.0)
    node, _ = ex._arrive(meet(0.3, 0.1, PLACE, 73, 4.0, 1.45))
    return ex, pair, node


def test_a_new_node_read_with_an_edge_more_than_its_one_look_alike_may_be_it():
    ex, pair, node = _new_edge_to_the_pair()
    assert ex.map.node(node).degree == 3  # the look-alike's ports, turned as read
    assert [h.mapping for h in ex.hyps.live] == [{node: (pair, h.mapping[node][1])}
                                                 for h in ex.hyps.live]  # fmt: skip
    assert len(ex.hyps.live) == 1
    assert any("read as node" in n.text and "looks like" in n.text for n in ex.notes)


def test_without_it_the_look_alike_is_no_candidate():
    ex, _, node = _new_edge_to_the_pair(ExplorerParams(look_alike_place=False))
    assert ex.map.node(node).degree == 4 and not ex.hyps.live

"""The slips of stop 29's census, each of which used to leave fig12's junctions mapped twice:
a moment off the edge, a U-turn on a long edge, a departure not held (the robot gone out of
the node another way, by known edges), a dead end whose length a walk estimated, a rival
turned further than drift allows, and a junction read with another degree.

The ring loses one wall's echo for a cycle or two now and then (six to ten of sixteen
transducers silent in a corridor); the tracer then reads itself off the edge, re-accesses
and is back on it a few centimetres on. Over fig1, fig12, fig13 and fig16 at drift
``paper`` (seeds 1-3, 1500 s) 218 of 283 such excursions came back within 0.3 m, having
driven no further. They used to make the whole edge's length a lower bound only, and most of
fig12's long edges had one.
"""

from __future__ import annotations

import math
from dataclasses import replace

import pytest

from hal.interfaces import NOMAD200_LIMITS
from hal.types import Odometry
from tests.test_explorer_split import meet
from tslam.core.explorer import Explorer, ExplorerParams
from tslam.core.localize import Hypothesis
from tslam.core.portmap import PortMap
from tslam.core.tracer import Behaviour, BoundaryReached


def _excursion(ex: Explorer, out_m: float, back_at: tuple[float, float]) -> None:
    """The tracer leaves the edge at (0, 0), drives ``out_m`` and is back tracing at
    ``back_at``."""
    ex.tracer.s.behaviour = Behaviour.ACCESS
    ex._watch_detour(Odometry(0.0, 0.0, 0.0, 0.0, 0.0, distance_m=10.0))
    ex.tracer.s.behaviour = Behaviour.TRACE
    ex._watch_detour(Odometry(*back_at, 0.0, 0.0, 1.0, distance_m=10.0 + out_m))


@pytest.mark.parametrize(
    ("out_m", "back_at", "blip_m", "disturbed", "detoured"),
    [
        (0.1, (0.05, 0.0), 0.3, False, False),  # a blip: nothing happened
        (0.1, (0.05, 0.0), 0.0, True, False),  # ... as before: the length is a bound
        (0.6, (0.4, 0.0), 0.3, True, False),  # a short excursion: the same edge, a bound
        (2.5, (0.4, 0.0), 0.3, True, False),  # backing and turning near a junction
        (5.0, (0.4, 0.0), 0.3, True, True),  # a long one: the robot does not know where
        (1.5, (1.2, 0.0), 0.3, True, True),  # ... or back too far from where it left
    ],
)
def test_a_blip_off_the_edge_leaves_its_length_whole(out_m, back_at, blip_m, disturbed, detoured):
    ex = Explorer(NOMAD200_LIMITS, params=ExplorerParams(blip_m=blip_m))
    _excursion(ex, out_m, back_at)
    assert (ex.disturbed, ex.detoured) == (disturbed, detoured)
    assert ex._tol().at_least is disturbed


@pytest.mark.parametrize("back_as", [Behaviour.TRACE, Behaviour.HOME, Behaviour.DEPART])
def test_an_excursion_ends_in_the_cycle_the_tracer_is_back_on_the_graph(back_as):
    # fig1 seed 5 re-accessed 0.2 m short of a dead end's corner; the cycle in which access
    # paired two walls again also found the corner, so the tracer was departing from it
    # when the excursion was judged, and the corner was mapped apart from the junction.
    ex = Explorer(NOMAD200_LIMITS)
    ex._odo = Odometry(0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
    ex._choose(meet(0.0, 0.0, [0, 120, 240], None, None))
    ex.tracer.s.behaviour = Behaviour.ACCESS
    ex._watch_detour(Odometry(1.0, 0.0, 0.0, 0.0, 1.0, distance_m=1.0))
    assert ex.detoured
    ex.tracer.s.behaviour = back_as
    ex._watch_detour(Odometry(1.4, 0.0, 0.0, 0.0, 1.0, distance_m=1.6))
    assert ex.disturbed and not ex.detoured
    ex._on_boundary(BoundaryReached(0.0, 1.4, 0.0, 0.4, 1.4))
    (b,) = [n.id for n in ex.map.nodes() if n.kind == "boundary"]
    assert ex.map.node(b).ports[0] in {e for e in ex.map.node(1).ports if e is not None}


def test_a_blip_after_a_real_excursion_does_not_undo_it():
    ex = Explorer(NOMAD200_LIMITS)
    _excursion(ex, 0.6, (0.4, 0.0))
    _excursion(ex, 0.1, (0.05, 0.0))
    assert ex.disturbed and not ex.detoured


def _two_look_alikes(turn_deg: float, confirmed: int = 3) -> tuple[Explorer, int, int, int]:
    """Old nodes ``a`` and ``b`` alike but for ``b`` being turned ``turn_deg`` against ``a``
    in the odometry frame, and a fragment node ``x`` read as ``a`` is; each hypothesis has
    ``confirmed`` confirmations."""
    ex = Explorer(NOMAD200_LIMITS)
    deps = (0.0, 2 * math.pi / 3, 4 * math.pi / 3)
    turned = sorted((d + math.radians(turn_deg)) % (2 * math.pi) for d in deps)
    a = ex.map.add_meet(1.2, deps, (0.0, 0.0))
    b = ex.map.add_meet(1.2, turned, (10.0, 0.0))
    x = ex.map.add_meet(1.2, deps, (0.5, 0.0))
    ex.born.update({a: 0.0, b: 5.0, x: 20.0})
    ex.hyps.fragment.add(x)
    ex.hyps.live = [
        Hypothesis({x: (a, 0)}, confirmed=confirmed),
        Hypothesis({x: (b, 0)}, confirmed=confirmed),
    ]
    return ex, a, b, x


def test_a_rival_turned_further_than_drift_allows_does_not_keep_a_proven_one_waiting():
    # fig12 seed 5: the mirror-image rival of a proven hypothesis kept it waiting, and the
    # fragment grew round the triangle onto itself, where it could no longer be placed.
    ex, a, b, x = _two_look_alikes(60.0)
    assert ex._heading_misfits(ex.hyps.live[1]) == [x]
    renamed = ex._resolve(x)
    assert renamed.get(x, (None, 0))[0] == a
    assert not ex.map.has_node(x) and ex.map.has_node(b)


def test_a_rival_with_as_much_support_turned_just_past_the_bound_still_competes():
    # fig15 at drift severe, seed 2: the true placement, turned 60 degrees where 60 were
    # allowed, was set aside for its heading, and a look-alike a block over with the same
    # support merged nine places falsely. Turned 35 degrees where 29 are allowed, a rival
    # with as many confirmations keeps the other waiting; with fewer it does not.
    ex, a, b, x = _two_look_alikes(35.0)
    assert ex._heading_misfits(ex.hyps.live[1]) == [x]
    assert ex._resolve(x) == {}
    assert all(ex.map.has_node(n) for n in (a, b, x))
    ex, a, b, x = _two_look_alikes(35.0, confirmed=4)
    ex.hyps.live[1].confirmed = 3
    assert ex._resolve(x).get(x, (None, 0))[0] == a


def test_a_rival_set_aside_for_its_heading_asks_one_confirmation_more():
    # fig15 without drift, seed 2: with the turned rival set aside, the one left had the
    # two confirmations that prove a single hypothesis, and merged a column of crossings
    # onto the one beside it. Where places repeat, the fragment may be new and both wrong.
    ex, a, b, x = _two_look_alikes(60.0, confirmed=2)
    assert ex._resolve(x) == {}
    assert all(ex.map.has_node(n) for n in (a, b, x))


def test_two_rivals_that_both_fit_the_heading_are_not_merged():
    ex, a, b, x = _two_look_alikes(120.0)  # b is a turned by one port: alike to the heading
    assert not ex._heading_misfits(ex.hyps.live[1])
    assert ex._resolve(x) == {}
    assert all(ex.map.has_node(n) for n in (a, b, x))


@pytest.mark.parametrize(
    ("arrival_deg", "far_m", "bounce"),
    [
        (0, 20.0, True),  # back by the departure it left by: a U-turn
        (0, 0.0, False),  # ... as before: only within 1.5 m
        (120, 20.0, False),  # back by another edge: round a loop, for the map to prove
    ],
)
def test_a_u_turn_on_a_long_edge_is_back_at_the_node_it_left(arrival_deg, far_m, bounce):
    # fig12 seed 2: 9.3 m out along the long edge and back, and the junction mapped again.
    ex = Explorer(NOMAD200_LIMITS, params=ExplorerParams(bounce_far_m=far_m))
    ex._odo = Odometry(0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
    assert ex._choose(meet(0.0, 0.0, [0, 120, 240], None, None)) == 0  # off east
    ex._odo = Odometry(0.1, 0.0, 0.0, 0.0, 9.0, 9.0)
    ex._choose(meet(0.1, 0.0, [0, 120, 240], arrival_deg, 9.0))
    assert (ex.notes[-1].text == "back at node 1: departure 0 could not be held") is bounce
    assert len(ex.map.nodes()) == (1 if bounce else 2)


def _triangle() -> tuple[Explorer, dict[str, int], dict[str, dict[int, int]]]:
    """fig12's shape: junctions A, B and C alike, 5 m apart along A-B and B-C, 10 m along
    A-C (round a block), each with a third departure to a dead end, C's evenly spread;
    returns the explorer, the nodes, and per node the port toward each bearing (degrees)."""
    ex = Explorer(NOMAD200_LIMITS)
    bearings = {"A": (0, 60, 180), "B": (180, 120, 300), "C": (240, 0, 120)}
    where = {"A": (0.0, 0.0), "B": (5.0, 0.0), "C": (2.5, 4.3)}
    nodes, ports = {}, {}
    for name, degs in bearings.items():
        deps = sorted(math.radians(d) for d in degs)
        nodes[name] = ex.map.add_meet(0.9, deps, where[name])
        ports[name] = {d: deps.index(math.radians(d)) for d in degs}
        ex.born[nodes[name]] = 0.0
    ex.map.connect(nodes["A"], ports["A"][0], nodes["B"], ports["B"][180], 5.0)
    ex.map.connect(nodes["B"], ports["B"][120], nodes["C"], ports["C"][0], 5.2)
    ex.map.connect(nodes["A"], ports["A"][60], nodes["C"], ports["C"][240], 10.0)
    return ex, nodes, ports


@pytest.mark.parametrize("heading_read", [True, False])
def test_the_other_way_round_a_triangle_is_recognised_by_heading(heading_read):
    # fig12 seed 8: meant to take the 10 m edge from A, the robot went by B, through it
    # unhomed, and came to C after 10.3 m by the edge from B. C's departures are evenly
    # spread: by the signature alone it could be C reached by the 10 m edge, the map then
    # turned a third of a turn at C, and every departure after it wrong.
    ex, nodes, ports = _triangle()
    a, c = nodes["A"], nodes["C"]
    ex.here, ex.leaving = a, (a, ports["A"][60])
    ex._odo = Odometry(2.5, 4.3, 0.0, 0.0, 100.0, 10.3) if heading_read else None
    ev = meet(2.5, 4.3, [240, 0, 120], 0, 10.3)
    node, rot = ex._identify(ev)
    assert node == c
    arrived_by = (ev.arrival_index + rot) % 3
    if heading_read:
        assert arrived_by == ports["C"][0]  # from B
        assert ex.notes[-1].text.endswith("went another way, recognised node 3")
    else:
        assert arrived_by == ports["C"][240]  # taken for the 10 m edge: turned


@pytest.mark.parametrize("estimated", [True, False])
def test_a_dead_end_whose_length_a_walk_estimated_is_matched_with_more_slack(estimated):
    # fig12 seed 10: through its junction unhomed into a dead end, the robot mapped the dead
    # end's edge as the way's remainder, 1.17 m; back along it, it homed at the junction
    # after 1.55 m, 4 cm beyond the tolerance, and went lost.
    ex, nodes, ports = _triangle()
    a = nodes["A"]
    b = ex.map.add_boundary(0.4, (-1.0, 0.5))
    e = ex.map.connect(a, ports["A"][180], b, 0, 1.17)
    if estimated:
        ex.estimated.add(e)
    ex.here, ex.leaving = b, (b, 0)
    ex._odo = Odometry(0.0, 0.0, 0.0, 0.0, 50.0, 50.0)
    node, _ = ex._identify(meet(0.0, 0.0, [0, 60, 180], 180, 1.55))
    assert (node == a) is estimated
    assert (e in ex.estimated) is False  # measured now, or never estimated


@pytest.mark.parametrize(("way_deg", "recognised"), [(0, True), (180, False)])
def test_a_departure_not_held_is_told_by_the_way_the_robot_went(way_deg, recognised):
    # fig12 seed 12: sent down A's unexplored departure, the robot turned back after 0.3 m,
    # went through A and along its known edge to B. Only the way it went tells that from a
    # new place down the unexplored departure that looks like B and lies as far.
    ex, nodes, ports = _triangle()
    a, b = nodes["A"], nodes["B"]
    deps = ex.map.node(a).departures_rad
    ex._last_visit = (a, deps, PortMap.rotation(0, 3, None), 0.0, 0.0)
    ex.here, ex.leaving = a, (a, ports["A"][180])
    ex.paths.restart()
    heading = math.radians(way_deg)
    for i in range(101):
        s = 0.05 * i
        ex.paths.add(Odometry(s * math.cos(heading), s * math.sin(heading), 0.0, 0.0, i, s))
    ex._odo = Odometry(5.0, 0.0, 0.0, 0.0, 100.0, 5.0)
    node, _ = ex._identify(meet(5.0, 0.0, [180, 120, 300], 180, 5.0))
    assert (node == b) is recognised
    assert any(n.text.endswith("went another way, recognised node 2") for n in ex.notes) is (
        recognised
    )


@pytest.mark.parametrize("misread, follow", [(False, True), (True, True), (True, False)])
def test_what_lies_beyond_a_junction_read_with_another_degree_tests_no_hypothesis(
    misread, follow
):
    # fig14 seed 1 without drift: a lab junction read with three edges, not four, was left by
    # what its angle match took for the edge to one look-alike; the robot went along another
    # to a second look-alike as far, which confirmed a wrong hypothesis: a false merge. Since
    # stop 51 (``unsure_follow``) the hypothesis follows the robot there all the same, with
    # no confirmation (tests/test_explorer_unsure_follow.py).
    ex, nodes, ports = _triangle()
    ex.p = replace(ex.p, unsure_follow=follow)
    a, b = nodes["A"], nodes["B"]
    x = ex.map.add_meet(0.9, ex.map.node(a).departures_rad, (20.0, 0.0))
    ex.hyps.fragment.add(x)
    h = Hypothesis({x: (a, 0)}, confirmed=1)
    ex.hyps.live = [h]
    if misread:
        ex._misread = x
    ex._leave(x, ports["A"][0])  # toward what A's edge to B is
    assert ex.unsure_departure is misread
    ex._identify(meet(25.0, 0.0, [180, 120, 300], 180, 5.0))
    assert h in ex.hyps.live
    assert h.confirmed == (1 if misread else 2)
    placed = h.mapping.get(max(n.id for n in ex.map.nodes()), (None, 0))[0] == b
    assert placed is (not misread or follow)


@pytest.mark.parametrize(
    ("way_deg", "port_deg"),
    [
        (240, 240),  # out as planned
        (0, 0),  # clearly along the other unexplored departure: its edge
        (300, 240),  # between the two: the plan stands
        (120, 240),  # along the known edge to the dead end: for _went_otherwise to say
    ],
)
def test_an_edge_ends_the_unexplored_departure_the_way_out_took(way_deg, port_deg):
    # fig16 seed 4 (switch vertex): sent into the indent, the robot went down the corridor;
    # mapped as the indent's edge, the corridor's junction was not recognised from below.
    ex = Explorer(NOMAD200_LIMITS)
    ex._odo = Odometry(0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
    ex._choose(meet(0.0, 0.0, [0, 120, 240], 120, None))  # arrived along 120
    node = ex.here
    deps = ex.map.node(node).departures_rad
    ports = {round(math.degrees(deps[i])) % 360: i for i in range(3)}
    dead_end = ex.map.add_boundary(0.4, (-0.5, 0.87))
    ex.map.connect(node, ports[120], dead_end, 0, 1.0)
    ex._leave(node, ports[240])
    ex._last_visit = (node, deps, PortMap.rotation(0, 3, None), 0.0, 0.0)
    ex.paths.restart()
    heading = math.radians(way_deg)
    for i in range(61):
        s = 0.05 * i
        ex.paths.add(Odometry(s * math.cos(heading), s * math.sin(heading), 0.0, 0.0, i, s))
    ex._odo = Odometry(3.0 * math.cos(heading), 3.0 * math.sin(heading), 0.0, 0.0, 60.0, 3.0)
    new, _ = ex._identify(meet(3.0, 0.0, [180, 60, 300], 180, 3.0))
    (edge,) = [e for e in ex.map.edges() if new in (e.u, e.v)]
    assert ex.map.node(node).ports[ports[port_deg]] == edge.id
    assert ex.leaving == (node, ports[port_deg])


@pytest.mark.parametrize(
    ("length_m", "bearings_deg", "bounce"),
    [
        (0.06, [2, 92, 182], True),  # the same junction, one of its edges not heard
        (0.5, [2, 92, 182], False),  # further on: a junction of its own
        (0.06, [45, 135, 225], False),  # its edges elsewhere: not this junction
    ],
)
def test_a_junction_read_again_with_an_edge_fewer_is_the_same_node(length_m, bearings_deg, bounce):
    # fig13 seed 1: its 0.29 m pair read as one place with four edges; the robot set off,
    # homed again 6 cm on, read three edges there, and the junction was mapped twice.
    ex = Explorer(NOMAD200_LIMITS)
    ex._odo = Odometry(0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
    ex._choose(meet(0.0, 0.0, [0, 90, 180, 270], None, None))
    node, port = ex.leaving
    ex._odo = Odometry(0.05, 0.0, 0.0, 0.0, 9.0, length_m)
    ex._choose(meet(0.05, 0.0, bearings_deg, bearings_deg[0], length_m))
    assert len(ex.map.nodes()) == (1 if bounce else 2)
    if bounce:
        note = f"back at node {node}, read with 3 edges: departure {port} not held"
        assert ex.notes[-1].text == note
        assert ex.here == node


@pytest.mark.parametrize("placed", [False, True])
def test_the_point_just_left_read_again_with_more_edges_a_hop_on_is_its_place(placed):
    # fig16 seed 3: the corridor's meet point read alone (up, down, and west into the
    # indent), then the weak one 0.36 m west read with the place's four edges; mapped as a
    # new node, and the corridor's point was mapped again when the robot came back to it.
    ex = Explorer(NOMAD200_LIMITS)
    ex._odo = Odometry(0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
    ex._choose(meet(0.0, 0.0, [90, 180, 270], 270, None))
    node = ex.here
    deps = ex.map.node(node).departures_rad
    ports = {round(math.degrees(deps[i])) % 360: i for i in range(3)}
    down = ex.map.add_meet(1.0, (0.5, 1.5, 3.0), (0.0, -5.0))
    edge = ex.map.connect(node, ports[270], down, 1, 5.0)
    if placed:  # an open hypothesis says where the node is: its ports must stay as they are
        other = ex.map.add_meet(1.1, deps, (9.0, 9.0))
        ex.hyps.live.append(Hypothesis({node: (other, 0)}))
    ex._leave(node, ports[180])
    ex._last_visit = (node, deps, PortMap.rotation(0, 3, None), 0.0, 0.0)
    ex._odo = Odometry(-0.36, 0.0, 0.0, 0.0, 30.0, 0.36)
    ex._identify(meet(-0.36, 0.0, [90, 135, 225, 270], 90, 0.36))
    assert len([n for n in ex.map.nodes() if n.kind == "meet"]) == (3 if placed else 2)
    place = ex.map.node(node)
    if placed:
        assert place.degree == 3
    else:
        assert place.degree == 4
        assert ex.notes[-1].text == f"node {node} read again as its place, with 4 edges"
        assert place.ports[3] == edge and ex.map.edge(edge).other_end(down, 1) == (node, 3)
        assert ex.map.unexplored()[:3] == [(node, 0), (node, 1), (node, 2)]


@pytest.mark.parametrize(
    ("back_at", "straight_rejoin_m", "detoured"),
    [
        ((1.9, 0.05), 3.0, False),  # straight on down the edge: the same edge
        ((1.9, 0.05), 0.0, True),  # ... as up to stop 41: lost, 0.9 m beyond rejoin_m
        ((-1.9, 0.0), 3.0, True),  # back the way it came: not on along this edge
        ((1.65, 0.95), 3.0, True),  # 30 degrees off the course
        ((3.4, 0.0), 3.0, True),  # straight on, but too far for dead reckoning to say
    ],
)
def test_an_excursion_straight_on_along_the_course_keeps_the_edge(
    back_at, straight_rejoin_m, detoured
):
    """office:1 seed 2: past a room's door the ring merged the jambs behind into one
    obstacle, and the robot accessed away from it straight down the edge they define, 1.9 m
    to the room's meet point; the explorer took it for lost and started a new fragment."""
    ex = Explorer(NOMAD200_LIMITS, params=ExplorerParams(straight_rejoin_m=straight_rejoin_m))
    ex.tracer.s.tangent = (1.0, 0.0)  # the course as the excursion began
    _excursion(ex, math.hypot(*back_at) + 0.05, back_at)
    assert ex.detoured is detoured

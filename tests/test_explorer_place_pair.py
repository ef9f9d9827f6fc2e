"""Two meet nodes a short edge apart, each read as part of one place (fig16's corridor meet
point and the weak one 0.36 m into the indent), become one node, and what was mapped twice
beyond them is merged (``tslam/core/place_pair.py``)."""

from __future__ import annotations

import math

from hal.interfaces import NOMAD200_LIMITS
from tests.test_explorer_past import _add, meet
from tslam.core.explorer import Explorer, ExplorerParams
from tslam.core.localize import Hypothesis
from tslam.core.portmap import PortMap

CORRIDOR = [90, 163, 197, 270]  # the place read at the corridor's point: N, indent x2, S
WEAK_AS_PLACE = [85, 150, 212, 275]  # ... and at the weak point, 0.37 m west
WEAK_ALONE = [0, 150, 210]  # the weak point read alone: east to the corridor's, indent x2
SOUTH = [90, 200, 340]  # the corridor's south end


def _boundary(ex: Explorer, x: float) -> int:
    return ex.map.add_boundary(0.45, (x, 0.0))


def _degrees(ex: Explorer, n: int) -> list[int]:
    return [round(math.degrees(b)) % 360 for b in ex.map.node(n).departures_rad]


def _edge_between(ex: Explorer, a: int, b: int) -> list[float]:
    return [e.length_m for e in ex.map.edges() if {e.u, e.v} == {a, b}]


def _both_as_place() -> tuple[Explorer, dict[str, int]]:
    """The corridor's point C and the weak point W, each mapped with the place's four
    edges, joined by a 0.37 m edge (C's lower indent port to W's north port, as fig16 seed 6
    mapped it); each led south to a junction of its own (S1, S2), and W to a dead end."""
    ex = Explorer(NOMAD200_LIMITS)
    c = _add(ex, 1.14, CORRIDOR, 0.0)
    w = _add(ex, 0.89, WEAK_AS_PLACE, -0.37)
    s1, s2 = _add(ex, 1.0, SOUTH, 5.0), _add(ex, 1.0, SOUTH, 5.1)
    b = _boundary(ex, -0.8)
    ex.map.connect(c, CORRIDOR.index(197), w, WEAK_AS_PLACE.index(85), 0.37)
    ex.map.connect(c, CORRIDOR.index(270), s1, SOUTH.index(90), 5.0)
    ex.map.connect(w, WEAK_AS_PLACE.index(275), s2, SOUTH.index(90), 5.1)
    ex.map.connect(w, WEAK_AS_PLACE.index(212), b, 0, 0.5)
    return ex, {"c": c, "w": w, "s1": s1, "s2": s2, "b": b}


def _stand_at_w(ex: Explorer, w: int) -> tuple[int, PortMap] | None:
    ev = meet(-0.37, 0.0, WEAK_AS_PLACE, 212, 0.5, 0.89)
    pm = PortMap(tuple(range(4)), WEAK_AS_PLACE.index(212))
    return ex._contract_pair(ev, w, pm)


def test_two_nodes_of_one_place_become_one_and_what_both_led_to_merges():
    ex, n = _both_as_place()
    stand = _stand_at_w(ex, n["w"])
    assert stand is not None
    node, pm = stand
    assert node == n["c"]  # the older node stays
    assert not ex.map.has_node(n["w"]) and not ex.map.has_node(n["s2"])
    assert _edge_between(ex, n["c"], n["c"]) == []  # the edge between the points is gone
    # The place keeps the corridor's reading; its lower indent port, which held the edge to
    # the weak point, now holds the weak point's edge to the dead end.
    assert _degrees(ex, n["c"]) == CORRIDOR
    ports = ex.map.node(n["c"]).ports
    assert ex.map.edge(ports[CORRIDOR.index(197)]).other_end(n["c"], 2)[0] == n["b"]
    assert ex.map.edge(ports[CORRIDOR.index(270)]).other_end(n["c"], 3)[0] == n["s1"]
    assert ports[CORRIDOR.index(163)] is None  # still to explore
    assert math.isclose(ex.map.node(n["c"]).clearance_m, (1.14 + 0.89) / 2)
    # The robot stands where it stood: the weak point's departures are the place's ports.
    assert pm.index == (0, 1, 2, 3) and pm.arrival == 2
    # Recorded as a merge (scored for false merges like any other) and said.
    assert len(ex.merges) == 1
    assert {(d, r) for d, r, _, _ in ex.merges[0].pairs} == {(n["w"], n["c"]), (n["s2"], n["s1"])}
    assert any("read as one place" in note.text for note in ex.notes)


def test_a_point_read_alone_goes_into_its_place():
    # fig16 seed 9: C read as the place, W alone with three edges; C's other indent edge
    # went through W unhomed to the dead end W's own edge had reached: one corner, twice.
    ex = Explorer(NOMAD200_LIMITS)
    c, w = _add(ex, 1.14, CORRIDOR, 0.0), _add(ex, 0.88, WEAK_ALONE, -0.39)
    b_up, b_down, b_again = _boundary(ex, -0.8), _boundary(ex, -0.9), _boundary(ex, -0.85)
    ex.map.connect(c, CORRIDOR.index(163), w, WEAK_ALONE.index(0), 0.39)
    ex.map.connect(w, WEAK_ALONE.index(150), b_up, 0, 0.49)
    ex.map.connect(w, WEAK_ALONE.index(210), b_down, 0, 0.52)
    ex.map.connect(c, CORRIDOR.index(197), b_again, 0, 0.88)  # measured from C, via W
    ev = meet(0.0, 0.0, CORRIDOR, 90, 5.0, 1.14)
    stand = ex._contract_pair(ev, c, PortMap(tuple(range(4)), 0))
    assert stand is not None and stand[0] == c
    assert not ex.map.has_node(w) and not ex.map.has_node(b_again)
    ports = ex.map.node(c).ports
    assert ex.map.edge(ports[CORRIDOR.index(163)]).other_end(c, 1)[0] == b_up
    assert ex.map.edge(ports[CORRIDOR.index(197)]).other_end(c, 2)[0] == b_down
    assert ex.span[c] == 0.39  # its edges were measured from either point


def test_the_robot_standing_at_the_point_read_alone_stands_at_the_place():
    ex = Explorer(NOMAD200_LIMITS)
    c, w = _add(ex, 1.14, CORRIDOR, 0.0), _add(ex, 0.88, WEAK_ALONE, -0.39)
    ex.map.connect(c, CORRIDOR.index(163), w, WEAK_ALONE.index(0), 0.39)
    ev = meet(-0.39, 0.0, WEAK_ALONE, 0, 0.39, 0.88)
    stand = ex._contract_pair(ev, w, PortMap((0, 1, 2), 0))
    assert stand is not None
    node, pm = stand
    assert node == c and len(pm.index) == 4
    # Each of the place's ports is the reading's departure nearest its bearing: the indent's
    # two as read, north and south the east departure (the reading has none nearer).
    assert pm.index[CORRIDOR.index(163)] == WEAK_ALONE.index(150)
    assert pm.index[CORRIDOR.index(197)] == WEAK_ALONE.index(210)
    assert pm.arrival is None  # it came from inside the place


def test_not_when_the_bearings_disagree_or_the_edge_is_long():
    ex, n = _both_as_place()
    # Its lower indent edge 28 degrees off the corridor point's: another junction.
    deps = [math.radians(b) for b in (85, 150, 240, 275)]
    ex.map.reread(n["w"], deps, 0.89, {0: 0, 1: 1, 2: 2, 3: 3})
    assert _stand_at_w(ex, n["w"]) is None
    ex, n = _both_as_place()
    (e,) = [e.id for e in ex.map.edges() if {e.u, e.v} == {n["c"], n["w"]}]
    ex.map.add_measurement(e, 1.5)  # the edge is some metres long: two junctions
    ex.map.add_measurement(e, 1.5)
    assert ex.map.edge(e).length_m > ExplorerParams().pair_contract_m
    assert _stand_at_w(ex, n["w"]) is None
    assert ex.map.has_node(n["w"]) and not ex.merges


def test_not_while_a_hypothesis_is_open_nor_when_switched_off():
    ex, n = _both_as_place()
    ex.hyps.live = [Hypothesis({n["s2"]: (n["s1"], 0)}, confirmed=1)]
    assert _stand_at_w(ex, n["w"]) is None
    ex, n = _both_as_place()
    ex.p = ExplorerParams(pair_contract_m=0.0)
    assert _stand_at_w(ex, n["w"]) is None and ex.map.has_node(n["w"])


def test_not_when_what_both_led_to_differs():
    # S2 a junction of another shape: the corridor south of the two is not one corridor.
    ex, n = _both_as_place()
    ex.map.reread(n["s2"], [math.radians(b) for b in (90, 150, 300)], 1.0, {0: 0})
    before = ex.map.to_dict()
    assert _stand_at_w(ex, n["w"]) is None
    assert ex.map.to_dict() == before

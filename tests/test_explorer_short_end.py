"""A dead end reached short along a mapped edge to a junction is the edge not held: the robot
goes back to the junction it left and tries again, once, instead of taking itself for lost
(``tslam/core/short_ends.py``)."""

from __future__ import annotations

from dataclasses import replace

from hal.interfaces import NOMAD200_LIMITS
from hal.types import Odometry
from tests.test_explorer_split import drive, meet
from tslam.core.explorer import Explorer, ExplorerParams
from tslam.core.tracer import BoundaryReached


def sent_along_the_edge(params: ExplorerParams | None = None) -> tuple[Explorer, float]:
    """Junction 1 at (0, 0) and junction 2 3 m east, the edge between them traced out and
    back; then the robot, held at 1, is sent to 2 along it."""
    ex = Explorer(NOMAD200_LIMITS, params=params)
    ex._odo = Odometry(0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
    assert ex._choose(meet(0.0, 0.0, [0, 120, 240], None, None)) == 0
    d = drive(ex, [(0.0, 0.0), (3.0, 0.0)], 0.0)
    assert ex.goto(1) is None
    ex._choose(meet(3.0, 0.0, [180, 60, 300], 180, 3.0))
    d = drive(ex, [(3.0, 0.0), (0.0, 0.0)], d)
    ex._choose(meet(0.0, 0.0, [0, 120, 240], 0, 3.0))
    assert ex.held and [(e.u, e.v) for e in ex.map.edges()] == [(1, 2)]
    assert ex.goto(2) is None
    assert ex.leaving == (1, 0)
    return ex, d


def dead_end_and_back(ex: Explorer, d: float, home: tuple[float, float] = (0.02, 0.01)) -> float:
    """A dead end 1.4 m out along the edge, and back to ``home`` (dead reckoned)."""
    d = drive(ex, [(0.0, 0.0), (1.4, 0.1)], d)
    ex._on_boundary(BoundaryReached(0.0, 1.4, 0.1, 0.44, 1.4))
    return drive(ex, [(1.4, 0.1), home], d)


def test_a_dead_end_short_along_a_mapped_edge_sends_the_robot_back_to_try_again():
    ex, d = sent_along_the_edge()
    d = dead_end_and_back(ex, d)
    assert "found a dead end 1.40 m out: back to node 1" in ex.notes[-1].text
    assert ex.leaving == (1, 0) and len(ex.map.nodes()) == 2  # no boundary mapped
    k = ex._choose(meet(0.02, 0.01, [1, 121, 241], 1, 1.4))
    assert ex.notes[-1].text == "back at node 1 from the dead end: departure 0 could not be held"
    assert k == 0 and ex.leaving == (1, 0)  # off along the edge again
    assert [(e.u, e.v, e.length_m) for e in ex.map.edges()] == [(1, 2, 3.0)]
    assert not any(n.text.startswith("lost") for n in ex.notes[1:])
    assert ex._avoid() == {}  # an edge not held is no edge that leads elsewhere
    # The way out and back is no pass over edge 1 (a pass says where the edge runs).
    assert ex.paths.get(1) is None or ex.paths.get(1).length_m > 2.5
    # Once only (``bounce_retries``): a second dead end there is what it looks like.
    dead_end_and_back(ex, d)
    assert "found a boundary: node 3" in ex.notes[-1].text
    assert len(ex.map.nodes()) == 3


def test_back_elsewhere_or_with_the_switch_off_the_robot_is_lost_as_before():
    ex, d = sent_along_the_edge(replace(ExplorerParams(), short_end_back=False))
    assert ex._avoid() == {}
    dead_end_and_back(ex, d)
    assert "found a boundary: node 3" in ex.notes[-1].text
    # Set out along edge 1 and lost: planning counts it 20 m longer from now on.
    assert ex._avoid() == {1: 20.0}
    # Dead reckoning puts the robot 1 m from where it left: not that junction.
    ex, d = sent_along_the_edge()
    dead_end_and_back(ex, d, home=(1.0, 1.0))
    ex._choose(meet(1.0, 1.0, [1, 121, 241], 1, 1.4))
    assert not any("from the dead end" in n.text for n in ex.notes)
    assert ex.notes[-1].text.startswith("lost (not back where node 1 was left for the dead end)")
    assert ex._avoid() == {1: 20.0}
    assert len(ex.map.nodes()) == 3


def test_a_dead_end_out_by_an_unexplored_departure_is_that_departures():
    ex, d = sent_along_the_edge()
    # Sent east along edge 1, the robot went out north-west, along the unexplored departure
    # at 120 degrees, to a dead end as far as the one above.
    d = drive(ex, [(0.0, 0.0), (-0.7, 1.21)], d)
    ex._on_boundary(BoundaryReached(0.0, -0.7, 1.21, 0.44, 1.4))
    assert "departure 0 of node 1 not held: went out by departure 1" in [n.text for n in ex.notes]
    assert not any("back to node 1" in n.text for n in ex.notes)
    edges = {(e.u, e.port_u, e.v): e.length_m for e in ex.map.edges()}
    assert edges == {(1, 0, 2): 3.0, (1, 1, 3): 1.4}
    assert ex.map.node(3).kind == "boundary" and ex.leaving == (3, 0)

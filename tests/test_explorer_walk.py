"""The robot went through a junction without homing there (a weak meet point, or the node it
had just left when a departure was not held): the traversal's own path says where it went,
instead of the robot calling itself lost or mapping a place twice."""

from __future__ import annotations

import math

import pytest

from hal.interfaces import NOMAD200_LIMITS
from hal.types import Odometry
from tests.test_explorer_split import drive, meet
from tests.tracer_paths import STOP25
from tslam.core.explorer import Explorer, ExplorerParams
from tslam.programs.sim_cmd import explore


def two_nodes() -> Explorer:
    """A at (0, 0) (departures 0, 120, 240 deg) and B at (4, 0) (60, 180, 300 deg), joined by
    a 4 m edge from A's port 0 to B's port 1; the robot is back at A."""
    ex = Explorer(NOMAD200_LIMITS)
    ex._odo = Odometry(0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
    assert ex._choose(meet(0.0, 0.0, [0, 120, 240], None, None)) == 0
    d = drive(ex, [(0.0, 0.0), (4.0, 0.0)], 0.0)
    ex._choose(meet(4.0, 0.0, [60, 180, 300], 180, 4.0))
    assert [(e.u, e.port_u, e.v, e.port_v) for e in ex.map.edges()] == [(1, 0, 2, 1)]
    ex._odo = Odometry(0.0, 0.0, 0.0, 0.0, d + 4.0, d + 4.0)
    return ex


def test_a_departure_not_held_that_comes_back_through_its_node_is_a_known_edge():
    ex = two_nodes()
    ex._leave(1, 1)  # out of A at 120 deg ...
    out = (0.2 * math.cos(math.radians(120)), 0.2 * math.sin(math.radians(120)))
    d = drive(ex, [(0.0, 0.0), out, (0.02, 0.0), (4.0, 0.0)], ex._odo.distance_m)
    assert d > 4.0
    # ... back through A, and along A's edge to B: B, arrived at by its port 1.
    ex._choose(meet(4.0, 0.0, [60, 180, 300], 180, 4.38))
    assert ex.here == 2 and len(ex.map.nodes()) == 2 and len(ex.map.edges()) == 1
    assert ex.notes[-1].text.startswith("departure 1 of node 1 not held: back through node(s) 1")
    assert ex.bounces[(1, 1)] == 1


def test_through_a_weak_junction_onto_its_unexplored_departure_is_a_new_edge_from_it():
    ex = two_nodes()
    ex._leave(1, 0)  # sent from A to B along the known edge
    # B does not show: the robot goes on through it, out along its 300 deg departure.
    c = (4.0 + 3.0 * math.cos(math.radians(300)), 3.0 * math.sin(math.radians(300)))
    drive(ex, [(0.0, 0.0), (4.0, 0.0), c], ex._odo.distance_m)
    node, _ = ex._arrive(meet(c[0], c[1], [120, 200, 330], 120, 7.0))
    assert node == 3
    assert any("went through node(s) 2 without homing" in n.text for n in ex.notes)
    new = [e for e in ex.map.edges() if 3 in (e.u, e.v)]
    assert len(new) == 1 and (new[0].u, new[0].port_u) == (2, 2)
    assert new[0].length_m == pytest.approx(3.0, abs=0.01)


def test_a_turn_at_the_junction_that_fits_no_departure_is_lost_not_guessed():
    ex = two_nodes()
    ex._leave(1, 0)
    c = (7.0, 0.0)  # straight on through B: 60 deg from either of its departures
    drive(ex, [(0.0, 0.0), (4.0, 0.0), c], ex._odo.distance_m)
    ex._arrive(meet(c[0], c[1], [60, 180, 300], 180, 7.0))
    assert ex.notes[-1].text.startswith("lost (expected node 2")


def test_fig12_departure_not_held_at_m2_is_recognised_and_the_map_completes():
    """fig12 seed 2: at 407 s the departure from m2 towards the cut corner is not held; the
    robot comes back through m2 and traces the known edge to m1. Without the walk back it
    mapped m1 again from an unexplored port and never closed the map (265 duplicates).
    With stop 25's tracer (``tests.tracer_paths``). Since stop 40's edge lengths (the ends'
    junction points dropped) the robot comes back another way, and the departure is
    recognised as not held there ("went another way, recognised node 3")."""
    run = explore("fig12", 2, "paper", duration_s=700.0, progress=False, tracer_params=STOP25)
    ex = run.explorer
    assert any("of node 2 not held:" in n.text for n in ex.notes), ex.notes
    assert ex.done and not ex.map.unexplored()
    assert sum(n.kind == "meet" for n in ex.map.nodes()) == 3 and len(ex.map.edges()) == 6


def test_fig16_weak_meet_points_passed_without_homing_still_give_the_whole_map():
    """fig16 seed 3: back from the indent's dead end the robot passes both weak meet points
    and homes only at the corridor's end; the walk puts that on the unexplored departure.

    With stop 25's tracer (``tests.tracer_paths``): of fig16 seeds 1-15 at drift paper none
    passes two weak meet points and still maps the whole corridor in 900 s with stop 26's
    (three pass them, and get lost; scratch loop, the calls below). And with the arbiter it was
    found with: a departure not held from the place tried again straight across it (stop 50)
    sends this tracer elsewhere, and the run, another way, is no test of the walk."""
    run = explore(
        "fig16",
        3,
        "paper",
        duration_s=900.0,
        progress=False,
        tracer_params=STOP25,
        params=ExplorerParams(place_straight_m=0.0),
    )
    ex = run.explorer
    assert any("went through node(s) 2, 1 without homing" in n.text for n in ex.notes)
    assert not any(n.text.startswith("lost (expected") for n in ex.notes), ex.notes
    assert ex.done and not ex.map.unexplored()
    assert sum(n.kind == "meet" for n in ex.map.nodes()) == 4 and len(ex.map.edges()) == 9

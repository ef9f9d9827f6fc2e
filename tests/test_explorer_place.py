"""A place of two close meet points (fig16's corridor junction and its weak meet point 0.36 m
into the indent) homed at either point: one node, whichever point the robot stands on, and a
departure that leaves from the other point is gone on by, not lost."""

from __future__ import annotations

import math

import pytest

from hal.interfaces import NOMAD200_LIMITS
from hal.types import Odometry
from tests.test_explorer_split import meet
from tslam.core.explorer import Explorer, ExplorerParams

# The corridor's point read as the place: up, into the indent (two edges), down.
PLACE = [70, 160, 200, 290]


def at_the_place(params: ExplorerParams | None = None) -> tuple[Explorer, int, dict[int, int]]:
    """The robot homed at the place at (0, 0), then sent into the indent by its 160-degree
    port; returns the explorer, the node and its ports by bearing."""
    ex = Explorer(NOMAD200_LIMITS, params=params)
    ex._odo = Odometry(0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
    ex._choose(meet(0.0, 0.0, PLACE, None, None))
    node = ex.here
    assert node is not None
    deps = ex.map.node(node).departures_rad
    ports = {round(math.degrees(b)) % 360: p for p, b in enumerate(deps)}
    ex._leave(node, ports[160])
    return ex, node, ports


@pytest.mark.parametrize("on", [True, False])
def test_homed_at_the_other_point_on_the_way_the_robot_goes_on_by_its_departure(on):
    ex, node, ports = at_the_place(ExplorerParams(on_through_place=on))
    # 0.36 m west, the weak point read alone: back east to the corridor's, and the indent's two.
    ex._odo = Odometry(-0.36, 0.0, 0.0, 0.0, 0.36, 0.36)
    ev = meet(-0.36, 0.0, [0, 152, 208], 0, 0.36)
    k = ex._choose(ev)
    assert len(ex.map.nodes()) == 1 and ex.here == node
    if on:
        assert ex.notes[-1].text == f"at node {node}'s other point, read with 3 edges: on by 1"
        assert not ex.bounces
        # Out by the weak point's 152-degree departure, still the node's 160-degree port.
        assert round(math.degrees(ev.departures_rad[k])) == 152
        assert ex.leaving == (node, ports[160])
    else:
        assert ex.bounces == {(node, ports[160]): 1}
        assert ex.notes[-1].text.endswith(f"departure {ports[160]} not held")


@pytest.mark.parametrize("same", [True, False])
def test_the_other_point_read_as_the_place_is_the_same_node(same):
    # Without a bounce as far as the other point (``bounce_place_m``), which is one node too.
    ex, node, ports = at_the_place(ExplorerParams(place_hop_same=same, bounce_place_m=0.0))
    # From the weak point the place's four edges leave a few degrees otherwise.
    ex._odo = Odometry(-0.34, 0.0, 0.0, 0.0, 0.34, 0.34)
    ex._choose(meet(-0.34, 0.0, [62, 152, 208, 298], 62, 0.34))
    meets = [n for n in ex.map.nodes() if n.kind == "meet"]
    assert len(meets) == (1 if same else 2)
    if same:
        assert ex.here == node and ex.span[node] == pytest.approx(0.34)
        assert ex.leaving == (node, ports[160])


def test_the_other_point_read_as_the_place_is_a_bounce_without_place_hop_same():
    ex, node, ports = at_the_place(ExplorerParams(place_hop_same=False))
    ex._odo = Odometry(-0.34, 0.0, 0.0, 0.0, 0.34, 0.34)
    ex._choose(meet(-0.34, 0.0, [62, 152, 208, 298], 62, 0.34))
    assert [n.id for n in ex.map.nodes() if n.kind == "meet"] == [node]
    assert ex.bounces == {(node, ports[160]): 1}


@pytest.mark.parametrize("slack", [True, False])
def test_back_from_a_dead_end_at_the_places_other_point_is_the_node(slack):
    ex, node, ports = at_the_place(ExplorerParams(place_span_slack=slack))
    ex._odo = Odometry(-0.36, 0.0, 0.0, 0.0, 0.36, 0.36)
    ex._choose(meet(-0.36, 0.0, [0, 152, 208], 0, 0.36))  # on by the 160-degree port
    # The dead end 0.52 m on from the weak point.
    dead = ex.map.add_boundary(0.4, (-0.8, 0.25))
    ex.map.connect(node, ports[160], dead, 0, 0.52)
    ex._leave(dead, 0)
    before = len(ex.notes)
    # Back, the weak point passed unhomed: homed at the corridor's point after 0.88 m, the
    # indent's pair read there as one edge.
    ex._odo = Odometry(0.0, 0.0, 0.0, 0.0, 2.0, 0.88)
    ex._choose(meet(0.0, 0.0, [70, 180, 290], 180, 0.88))
    lost = [n.text for n in ex.notes[before:] if n.text.startswith("lost")]
    if slack:
        assert ex.here == node and not lost
    else:
        assert lost and ex.here != node


def test_a_departure_gone_on_by_twice_is_not_held_the_third_time():
    # Sent back and forth between the two points, the robot is not getting out of the place.
    ex, node, ports = at_the_place()
    corridor = ex._last_visit
    for i in range(3):
        ex._last_visit = corridor
        ex._leave(node, ports[160])
        ex._odo = Odometry(-0.36, 0.0, 0.0, 0.0, 0.36 * (i + 1), 0.36)
        ex._choose(meet(-0.36, 0.0, [0, 152, 208], 0, 0.36))
    on_by = [n.text for n in ex.notes if n.text.endswith(f"on by {ports[160]}")]
    assert len(on_by) == 2
    assert ex.notes[-1].text.endswith(f"departure {ports[160]} not held")
    assert ex.bounces == {(node, ports[160]): 1}


def test_read_with_another_degree_where_it_stood_is_a_bounce_not_the_other_point():
    # 6 cm on, not 0.36 m: the same point, the departure not held (fig13 seed 1).
    ex, node, ports = at_the_place()
    ex._odo = Odometry(-0.06, 0.0, 0.0, 0.0, 0.06, 0.06)
    ex._choose(meet(-0.06, 0.0, [0, 152, 208], 0, 0.06))
    assert ex.notes[-1].text.endswith(f"departure {ports[160]} not held")
    assert ex.bounces == {(node, ports[160]): 1}

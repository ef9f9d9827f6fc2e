"""Shut in: the piece of map the robot is in has nothing left to explore, but another piece
has departures left. The GVG is connected, so some node here was read without an edge; the
robot comes back to each meet node of its piece by each of its edges, to read it again,
before it stops."""

from __future__ import annotations

import pytest

from hal.interfaces import NOMAD200_LIMITS
from hal.types import Odometry
from tests.test_explorer_past import _add, meet
from tslam.core.explorer import Explorer, ExplorerParams
from tslam.core.tracer import TracerParams
from tslam.programs.sim_cmd import explore, report

ROOM_DOOR = [0, 120, 240]  # the junction by the door, read without the door's edge
ROOM_FAR = [60, 180, 300]


def _shut_in(params: ExplorerParams | None = None) -> tuple[Explorer, int, int, int]:
    """A room mapped as a closed piece (two junctions 4 m apart, two dead ends each) and,
    out of reach, the corridor outside with a departure left. The robot stands at the door's
    junction. Returns the explorer, the two room junctions and the corridor node."""
    ex = Explorer(NOMAD200_LIMITS, params=params)
    door = _add(ex, 1.5, ROOM_DOOR, 0.0)
    far = _add(ex, 1.5, ROOM_FAR, 4.0)
    ex.map.connect(door, 0, far, 1, 4.0)
    for n, ports, x in ((door, (1, 2), 0.0), (far, (0, 2), 4.0)):
        for p in ports:
            b = ex.map.add_boundary(0.4, (x, 1.0))
            ex.map.connect(n, p, b, 0, 1.2)
    corridor = _add(ex, 1.0, [0, 90, 180], 0.0)
    b = ex.map.add_boundary(0.4, (-1.0, 3.0))
    ex.map.connect(corridor, 0, b, 0, 1.5)
    return ex, door, far, corridor


def test_shut_in_the_robot_goes_back_to_read_its_junctions_again():
    ex, door, _, corridor = _shut_in()
    assert ex.unexplored() == [(corridor, 1), (corridor, 2)]
    port = ex._shut_in_port(door)
    # The nearest arrival at a junction by an edge: back at this one from a dead end (2.4 m,
    # against 4 m to the far junction).
    assert port == 1
    dead_end = ex.map.edge(ex.map.node(door).ports[1]).other_end(door, 1)[0]
    ((step),) = ex.plan
    assert (step.node, step.next_node, step.arrival_port) == (dead_end, door, 1)
    assert ex.rechecked == {(door, 1)}
    assert f"back to node {door} by edge" in ex.notes[-1].text


def test_each_arrival_is_made_once_then_the_robot_stops():
    ex, door, far, _ = _shut_in()
    arrivals = set()
    for _ in range(20):
        path = ex._recheck_path(door)
        if not path:
            break
        last = path[-1]
        arrivals.add((last.next_node, last.arrival_port))
        # The path ends by arriving at a room junction, along an edge of the room.
        assert last.next_node in (door, far)
    # Both junctions, by each of their three edges; never the corridor, out of reach.
    assert arrivals == {(door, p) for p in range(3)} | {(far, p) for p in range(3)}
    assert ex._recheck_path(door) == []
    assert ex._shut_in_port(door) is None


def test_a_loop_back_to_the_same_node_is_come_back_by_at_each_end():
    ex = Explorer(NOMAD200_LIMITS)
    x = _add(ex, 1.5, ROOM_DOOR, 0.0)
    ex.map.connect(x, 0, x, 1, 6.0)  # round a pillar and back
    ex.map.connect(x, 2, ex.map.add_boundary(0.4, (0.0, -1.0)), 0, 1.2)
    _add(ex, 1.0, [0, 90, 180], 20.0)  # a piece out of reach, unexplored
    arrivals = []
    for _ in range(10):
        path = ex._recheck_path(x)
        if not path:
            break
        last = path[-1]
        far = ex.map.edge(last.edge).other_end(last.node, last.port)
        assert far == (last.next_node, last.arrival_port)  # each step as the map has it
        arrivals.append(far)
    assert sorted(arrivals) == [(x, 0), (x, 1), (x, 2)]


def test_with_nothing_left_anywhere_there_is_nothing_to_read_again():
    ex, door, _, corridor = _shut_in()
    (e,) = [e for e in ex.map.node(corridor).ports if e is not None]
    b = ex.map.edge(e).other_end(corridor, 0)[0]
    ex.map.remove_node(corridor)
    ex.map.remove_node(b)
    assert ex._recheck_path(door) == []
    assert ex._shut_in_port(door) is None


def test_a_robot_sent_to_a_node_holds_there_shut_in_or_not():
    ex, door, far, _ = _shut_in()
    ex._odo = Odometry(0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
    ex.leaving, ex.goal = (far, 1), door  # an operator's goto, on its last edge
    ex._choose(meet(0.0, 0.0, ROOM_DOOR, 0, 4.0, 1.5))
    assert ex.held and not ex.done and ex.goal is None
    assert [n.text for n in ex.notes] == [f"at node {door}, as ordered: holding"]
    assert ex.rechecked == set()


def test_the_switch_off_stops_the_robot_shut_in():
    ex, door, _, _ = _shut_in(ExplorerParams(recheck_shut_in=False))
    assert ex._shut_in_port(door) is None
    assert ex.rechecked == set()


@pytest.mark.parametrize("recheck", [True, False])
def test_office_2_seed_1_room_closed_on_itself(recheck: bool):
    """office:2 seed 1 at drift paper: lost in a room by its door, the robot mapped the room
    again as a piece of its own, its door junction read from the lower of its two points
    with three edges, and stopped at 1285 s, 'nothing left to explore from here', with 10 of
    the building's 402 places mapped. Come back to that junction from the room's far
    junction, it reads the door's edge; it goes out and maps on. As the run was before
    ``own_bearing_pair_m`` (stop 57), which re-rolls it from 1060 s on: a departure left by its
    own bearing out of the room's door junction then went out rather than back to its other
    point. And as before stop 58's rules for rooms' doors, which re-roll it too."""
    params = ExplorerParams(recheck_shut_in=recheck, own_bearing_pair_m=0.0)
    tracer = TracerParams(
        room_entry_m=0.0,
        sweep_silent_view=False,
        home_apart=False,
        door_steer_m=0.0,
        own_sides_along_rad=0.0,
    )
    run = explore("office:2", 1, "paper", 2000.0, progress=False, params=params,
                  tracer_params=tracer)  # fmt: skip
    texts = [n.text for n in run.explorer.notes]
    rep = report(run, "office:2", 1, "paper")
    if recheck:
        assert not run.explorer.done
        assert any("to read it again" in t for t in texts)
        assert any(t.endswith("read again as its place, with 4 edges") for t in texts)
        assert rep["found_places"] >= 16  # 20 of its 402 by 2000 s
    else:
        assert run.explorer.done
        assert any(t.startswith("nothing left to explore from here:") for t in texts)
        assert rep["found_places"] <= 12  # 10
    assert rep["false_merges"] == 0


def _given_up_in_the_room(params: ExplorerParams | None = None) -> tuple[Explorer, int, int]:
    """The room alone, the far junction's third dead end not held twice: given up. Returns
    the explorer and the two junctions."""
    ex, door, far, corridor = _shut_in(params)
    dead_end = ex.map.edge(ex.map.node(corridor).ports[0]).other_end(corridor, 0)[0]
    south = ex.map.edge(ex.map.node(far).ports[2]).other_end(far, 2)[0]
    for n in (corridor, dead_end, south):
        ex.map.remove_node(n)
    ex.bounces[(far, 2)] = ex.p.bounce_retries + 1
    ex.frozen.add((far, 2))
    return ex, door, far


def test_a_departure_given_up_is_tried_again_from_another_way_in():
    ex, door, far = _given_up_in_the_room()
    assert ex.unexplored() == []
    port = ex._shut_in_port(door)
    # The nearest way into the far junction: along the 4 m edge from here.
    assert port == 0 and ex.plan == []
    assert (far, 2) not in ex.frozen and ex.bounces[(far, 2)] == ex.p.bounce_retries
    edge = ex.map.node(door).ports[0]
    assert ex.notes[-1].text == (
        f"departure(s) 2 of node {far} given up: back to it by edge {edge} to try again"
    )
    # Given up again, it is tried from the far junction's other way in, then no more.
    ex.bounces[(far, 2)] += 1
    ex.frozen.add((far, 2))
    path = ex._retry_path(door)
    assert (path[-1].next_node, path[-1].arrival_port) == (far, 0)
    ex.bounces[(far, 2)] += 1
    ex.frozen.add((far, 2))
    assert ex._retry_path(door) == []
    assert ex._shut_in_port(door) is None


def test_the_switch_off_leaves_a_departure_given_up():
    ex, door, far = _given_up_in_the_room(ExplorerParams(retry_given_up=False))
    assert ex._shut_in_port(door) is None
    assert (far, 2) in ex.frozen


@pytest.mark.parametrize("retry", [True, False])
def test_fig16_seed_68_the_corridor_south_tried_again_from_the_north(retry: bool):
    """fig16 seed 68 at drift paper: back from the indent's dead end each time, the robot
    homed onto the indent's weak meet point, and leaving from there for the corridor south
    went into the dead end again, twice for each of two departures. It called exploration
    complete with two of the three places. Come back from the north, it homes onto the
    corridor's point and goes south."""
    run = explore(
        "fig16", 68, "paper", 1500.0, progress=False, params=ExplorerParams(retry_given_up=retry)
    )
    rep = report(run, "fig16", 68, "paper")
    texts = [n.text for n in run.explorer.notes]
    assert run.explorer.done
    assert rep["false_merges"] == 0
    if retry:
        assert any(t.endswith("given up: back to it by edge 2 to try again") for t in texts)
        assert rep["complete"]
    else:
        assert not rep["complete"] and rep["found_places"] == 2


def test_a_departure_given_up_stays_given_up_when_its_node_is_merged():
    """A merge renames node 9 to the kept node, its port p to port p + 1: what was tried at
    each port goes with it. Before stop 56 only ``frozen`` did, and the departure read as
    left by an ambiguity, never retried as one given up."""
    ex = Explorer(NOMAD200_LIMITS)
    kept = _add(ex, 1.5, ROOM_FAR, 0.0)
    ex.bounces[(9, 2)] = ex.p.bounce_retries + 1
    ex.frozen.add((9, 2))
    ex.went_along_another.add((9, 2))
    ex.rechecked.add((9, 0))
    ex._apply_renames({9: (kept, 1)})
    assert ex.frozen == ex.went_along_another == {(kept, 0)}
    assert ex.bounces == {(kept, 0): ex.p.bounce_retries + 1}
    assert ex.rechecked == {(kept, 1)}
    assert (
        ex._left_out()
        == f"; 1 departure(s) given up, not held when tried (node:departure {kept}:0)"
    )

"""Out of a room through its door: from office:1's room meet point 94 at (13.2, 4.24), 2.9 m
below a 1 m door, toward the corridor junction 95 at (13.2, 8.08) above it.

The explorer leaves by the door's own bearing, straight on until the ring sees the edge's two
obstacles straddle the way (``ExplorerParams.own_bearing_until_sides_m``): the jambs, which it
resolves only a metre or so from the door. Some 0.6 m out the wall round the door, 2.2 m ahead
and 17 degrees off the way, and a side wall 2.9 m off straddled it: the robot began tracing
them, the trace law dropped a pair 0.7 m apart, access backed it off the wall, and it traced
into the room's top-left corner (seed 2 of the exploration, at 376 s). A pair that straddles
the way must also be about as far (``ExplorerParams.own_bearing_pair_m``).
"""

from __future__ import annotations

import math

import pytest

from sim_backend.backend import SimBackend
from sim_backend.builtin_worlds import builtin_world
from sim_backend.world import PolygonWorld, StartPose
from tslam.core.explorer import ExplorerParams
from tslam.core.tracer import BoundaryReached, MeetPointReached, Tracer, TracerParams
from tslam.programs.sim_cmd import explore, report

CORRIDOR = (13.2, 8.08)
ROOM = (13.2, 4.24)


def _out_of_the_room(pair_m: float, seed: int) -> tuple[str, tuple[float, float]]:
    """Leave the room's meet point up toward the door by its own bearing, as the explorer
    does, its two sides ``pair_m`` apart at most (0: any): the kind of the first event more
    than 0.5 m from the start and the true position there."""
    office = builtin_world("office:1")
    start = StartPose(*ROOM, 0.0)
    world = PolygonWorld("office:1", office.boundary, office.obstacles, start, source="test")
    backend = SimBackend(world, seed=seed)
    tracer = Tracer(backend.limits, TracerParams())
    robot = backend.robot
    with backend:
        clock = backend.clock
        until = ExplorerParams().own_bearing_until_sides_m
        tracer.depart(math.pi / 2, backend.odometry(), until, pair_m)
        while clock.now() < 200.0:
            odo = backend.odometry()
            twist, events = tracer.step(backend.scan(), odo, backend.status(), clock.now())
            backend.command(twist)
            tp = robot.true_pose()
            away = math.dist((tp.x, tp.y), ROOM) > 0.5
            for ev in events:
                if away and isinstance(ev, (MeetPointReached, BoundaryReached)):
                    kind = "meet" if isinstance(ev, MeetPointReached) else "boundary"
                    return kind, (tp.x, tp.y)
            clock.sleep(0.1)
    raise AssertionError("no node within 200 s")


# Seeds 1-8 measured (scratch loop over the calls below): with the pair within 0.15, 0.3 or
# 0.45 m the robot reached the corridor junction in all eight; within 0.6 m (the trace law's
# ``off_edge_m``) in seeds 1, 4 and 8; without, in 1, 4 and 8 too, and it went into a top
# corner of the room in four and back down to meet point 93 in one.
@pytest.mark.parametrize("seed", [2, 3, 5])
def test_the_robot_goes_out_through_the_door(seed):
    kind, at = _out_of_the_room(ExplorerParams().own_bearing_pair_m, seed)
    assert kind == "meet" and math.dist(at, CORRIDOR) < 0.3, at


@pytest.mark.parametrize("seed", [2, 3, 5])
def test_without_the_pair_the_robot_traces_into_a_corner_of_the_room(seed):
    kind, at = _out_of_the_room(0.0, seed)
    assert kind == "boundary" and at[1] > 6.0 and abs(at[0] - ROOM[0]) > 2.0, at


def test_office_1_seed_2_leaves_its_first_room_and_maps_on():
    # The run of the docstring: at stop 57, without the pair it came back into the room each
    # time, and at 943 s had nothing left to explore, with 3 of the building's 339 places.
    # Since stop 58 (doors found from inside rooms, tests/test_room_entry.py) that run takes
    # another way before then, and maps on without the pair too (20 places at 2400 s against
    # 25): the tests above hold the pair's own effect. What stays is that the robot leaves.
    run = explore("office:1", 2, "paper", duration_s=2400.0, progress=False)
    rep = report(run, "office:1", 2, "paper")
    assert rep["false_merges"] == 0
    assert not rep["finished"] and rep["found_places"] >= 15

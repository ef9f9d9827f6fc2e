"""A room whose door is in the middle of a long wall (stop 58).

The floor: a 20 x 10 m building, a 1.9 m corridor along its south side, and two rooms of
9.85 x 7.8 m above it, each with a 1 m door in the middle of its south wall (x 4.5-5.5 and
14.5-15.5, wall at y 2.0-2.1). Its GVG has ten meet points; the door junctions inside the rooms
are (5.0, 5.98) and (15.0, 5.98), 1 m from the room's other two junctions on the room's long
edge, and 3.9 m from the door, whose jambs are then 15 degrees apart, inside one beam:
- on the way in, the ring merges the jambs behind the robot 1.1 m past the door; access drove
  on away from them, and the trace law took the room's edge left or right as noise had it, so
  the door's edge ended at one of the other junctions on one pass and the other on the next
  (``TracerParams.room_entry_m``: the junction is where access stands between the door behind
  and the far wall ahead);
- along the room's edge the junction never shows: it is stood at by the edge's length
  (``Tracer.arrive_after``), and left for the door by the door's own bearing, steering for the
  middle of the jambs once the ring sees between them (``TracerParams.door_steer_m``);
- from the corridor's junction in front of a door the sweep joined the jambs, 59 degrees
  apart with no echo between (the room is beyond the sonar's range that way), into one bent
  wall, and the corridor's junction was passed (``sweep.SILENT_VIEW_READINGS``).
"""

from __future__ import annotations

import json
import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from sim_backend.backend import SimBackend
from sim_backend.world import PolygonWorld, StartPose
from sim_backend.world_files import load_world
from tslam.core import doors
from tslam.core.sensing import Obstacle
from tslam.core.sweep import sweep_minima
from tslam.core.tracer import MeetPointReached, Tracer, TracerParams
from tslam.core.tracer_state import TracerState
from tslam.programs.sim_cmd import explore, report

CORRIDOR_JUNCTION = (15.0, 1.116)  # in front of the east room's door
DOOR_JUNCTION = (15.0, 5.98)  # inside the east room, 3.9 m from the door
EAST_JUNCTION = (16.0, 6.0)  # the room's junction east of it


def _box(x0: float, y0: float, x1: float, y1: float) -> list[list[float]]:
    return [[x0, y0], [x1, y0], [x1, y1], [x0, y1]]


FLOOR = {
    "name": "two_rooms",
    "boundary": _box(0.1, 0.1, 19.9, 9.9),
    "obstacles": [
        _box(0.0, 2.0, 4.5, 2.1),
        _box(5.5, 2.0, 14.5, 2.1),
        _box(15.5, 2.0, 20.0, 2.1),
        _box(9.95, 2.0, 10.05, 10.0),
    ],
    "start": {"x": 2.0, "y": 1.0, "theta": 0.0},
}


def _world(x: float, y: float, theta: float) -> PolygonWorld:
    return PolygonWorld(
        "two_rooms", FLOOR["boundary"], FLOOR["obstacles"], StartPose(x, y, theta), "test"
    )


def _first_meet(
    start: tuple[float, float, float],
    seed: int,
    params: TracerParams,
    arrive_after: tuple[float, tuple[float, ...]] | None = None,
) -> tuple[MeetPointReached, tuple[float, float]]:
    """From ``start`` (a junction, heading along the departure to take) depart straight
    ahead and trace: the first meet point more than 0.5 m on, and the true position there."""
    world = _world(*start)
    backend = SimBackend(world, seed=seed)
    tracer = Tracer(backend.limits, params)
    robot = backend.robot
    with backend:
        clock = backend.clock
        odo = backend.odometry()
        tracer.s.odometer.start(odo.x_m, odo.y_m)  # as at a node just reported
        tracer.depart(0.0, odo)
        if arrive_after is not None:
            tracer.arrive_after(*arrive_after)
        while clock.now() < 200.0:
            odo = backend.odometry()
            twist, events = tracer.step(backend.scan(), odo, backend.status(), clock.now())
            backend.command(twist)
            tp = robot.true_pose()
            for ev in events:
                if isinstance(ev, MeetPointReached) and math.dist((tp.x, tp.y), start[:2]) > 0.5:
                    return ev, (tp.x, tp.y)
            clock.sleep(0.1)
    raise AssertionError("no meet point within 200 s")


def _angle(a: float, b: float) -> float:
    return abs((a - b + math.pi) % (2 * math.pi) - math.pi)


# Scratch loop over seeds 1-6 (the calls below): the door junction stood at in all six,
# 0.01-0.11 m off, the way back to the door read within 4 degrees; without the rule the first
# meet point was the room's east junction in three and its west one in three. By length from
# the east junction: 0.04-0.09 m off, the door's edge read within 4 degrees.
@pytest.mark.parametrize("seed", [1, 2, 3])
def test_into_the_room_the_robot_stands_at_the_door_junction(seed):
    ev, at = _first_meet((*CORRIDOR_JUNCTION, math.pi / 2), seed, TracerParams())
    assert ev.found_by == "entry" and ev.degree == 3, ev
    assert math.dist(at, DOOR_JUNCTION) < 0.15, at
    # The way back is the door's edge, straight back down (the odometry frame's x axis is the
    # robot's heading at the start, north), and the room's two edges leave square to it.
    assert ev.arrival_index is not None
    back = ev.departures_rad[ev.arrival_index]
    assert _angle(back, math.pi) < math.radians(6.0), math.degrees(back)
    assert sorted(round(math.degrees(r)) for r in ev.relative_rad) == [0, 90, 270]


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_without_the_rule_the_door_edge_ends_at_another_junction(seed):
    params = TracerParams(room_entry_m=0.0)
    ev, at = _first_meet((*CORRIDOR_JUNCTION, math.pi / 2), seed, params)
    assert ev.found_by == "homing"
    assert math.dist(at, DOOR_JUNCTION) > 0.8 and abs(at[1] - DOOR_JUNCTION[1]) < 0.2, at


@pytest.mark.parametrize("seed", [1, 2])
def test_along_the_room_the_robot_stands_at_the_door_junction_by_length(seed):
    # West from the east junction, 1 m to the door junction: arriving from the east, the
    # way in is departure 0, the room's edge on west is half a turn off, the door's edge
    # three quarters (counter-clockwise: south).
    rel = (0.0, math.pi, 1.5 * math.pi)
    ev, at = _first_meet((*EAST_JUNCTION, math.pi), seed, TracerParams(), (1.0, rel))
    assert ev.found_by == "length" and ev.degree == 3
    assert abs(at[0] - DOOR_JUNCTION[0]) < 0.15 and abs(at[1] - DOOR_JUNCTION[1]) < 0.15, at
    assert ev.arrival_index is not None
    door = ev.departures_rad[(ev.arrival_index + 2) % 3]  # odometry: 0 is west, the start's way
    assert _angle(door, math.pi / 2) < math.radians(6.0), math.degrees(door)
    # Without it the junction is not there to the ring: the robot traces on to the next.
    ev, at = _first_meet((*EAST_JUNCTION, math.pi), seed, TracerParams())
    assert ev.found_by == "homing" and at[0] < 14.3, at


def _jambs_sweep(between: float) -> tuple[np.ndarray, np.ndarray]:
    """A sweep of 65 readings as at the corridor's junction in front of a door: the wall
    behind 0.98 m off, two jambs 1.03 and 1.05 m off 53 degrees apart, and ``between``
    (inf: no echo) in the 30 degrees of view between them."""
    b = np.radians(np.arange(65) * 360.0 / 65.0)
    d = np.full(65, np.inf)
    deg = np.degrees(b)
    d[(deg >= 5) & (deg <= 22)] = 1.03
    d[(deg > 22) & (deg < 58)] = between
    d[(deg >= 58) & (deg <= 78)] = 1.05
    d[(deg >= 200) & (deg <= 245)] = 0.98
    return b, d


def test_the_sweep_sees_a_doorway_with_no_echo_between_as_two_jambs():
    b, d = _jambs_sweep(math.inf)
    two = sweep_minima(b, d, silent_view=True)
    one = sweep_minima(b, d)
    assert [round(o.distance_m, 2) for o in two] == [0.98, 1.03, 1.05]
    assert [round(o.distance_m, 2) for o in one] == [0.98, 1.03]
    # A bend's vertex echoes between its two faces: a concave corner is one wall still.
    d[(np.degrees(b) > 36) & (np.degrees(b) < 44)] = 1.2
    assert len(sweep_minima(b, d, silent_view=True)) == 2


def _obstacle(bearing_deg: float, dist: float) -> Obstacle:
    b = math.radians(bearing_deg)
    return Obstacle(dist, dist * math.cos(b), dist * math.sin(b), -math.cos(b), -math.sin(b), b)


def test_a_door_ahead_is_its_two_jambs_either_side_of_the_way():
    p, s = TracerParams(), TracerState(sides_pair_m=0.45)
    jambs = [_obstacle(-20.0, 1.5), _obstacle(28.0, 1.6), _obstacle(90.0, 1.55)]
    mid, near = doors.door_ahead(p, s, jambs, 0.0)
    assert near == pytest.approx(1.5) and math.degrees(mid) == pytest.approx(4.3, abs=1.0)
    # A side wall abeam is no jamb; nor is a pair far apart in distance.
    assert doors.door_ahead(p, s, [_obstacle(-20.0, 1.5), _obstacle(90.0, 1.5)], 0.0) is None
    assert doors.door_ahead(p, s, [_obstacle(-20.0, 1.5), _obstacle(28.0, 2.2)], 0.0) is None


def _floor_file(tmp_path: Path) -> str:
    path = tmp_path / "two_rooms.json"
    path.write_text(json.dumps(FLOOR))
    return str(path)


def test_the_floor_of_two_rooms_is_explored_completely(tmp_path):
    world = _floor_file(tmp_path)
    run = explore(world, 2, "paper", duration_s=3000.0, progress=False)
    rep = report(run, world, 2, "paper")
    assert rep["false_merges"] == 0
    assert rep["complete"], {k: rep[k] for k in ("found_meet_points", "found_edges")}
    # Without the room's door junction the robot maps the door's edge onto one of the room's
    # other junctions on one pass and the other on the next, and the map never comes whole.
    params = replace(TracerParams(), room_entry_m=0.0)
    run = explore(world, 2, "paper", duration_s=3000.0, progress=False, tracer_params=params)
    rep = report(run, world, 2, "paper")
    assert rep["false_merges"] == 0 and not rep["complete"]
    assert rep["found_meet_points"] < rep["true_meet_points"]


def _floor_map(tmp_path: Path) -> Path:
    """The floor as a ROS map_server map at 5 cm a cell, with no start."""
    res, width, height = 0.05, 400, 200
    img = np.full((height, width), 254, dtype=np.uint8)

    def wall(x0: float, y0: float, x1: float, y1: float) -> None:
        rows = slice(height - round(y1 / res), height - round(y0 / res))
        img[rows, round(x0 / res) : round(x1 / res)] = 0

    for x0, y0, x1, y1 in [(0, 0, 20, 0.1), (0, 9.9, 20, 10), (0, 0, 0.1, 10), (19.9, 0, 20, 10)]:
        wall(x0, y0, x1, y1)
    for box in FLOOR["obstacles"]:
        (x0, y0), (x1, y1) = box[0], box[2]
        wall(x0, y0, x1, y1)
    (tmp_path / "floor.pgm").write_bytes(b"P5\n400 200\n255\n" + img.tobytes())
    path = tmp_path / "floor.yaml"
    path.write_text(
        "image: floor.pgm\nresolution: 0.05\norigin: [0.0, 0.0, 0.0]\nnegate: 0\n"
        "occupied_thresh: 0.65\nfree_thresh: 0.196\n"
    )
    return path


def test_a_map_with_no_start_begins_at_a_corridor_junction_and_is_explored(tmp_path):
    path = _floor_map(tmp_path)
    world = load_world(path)
    # Not the farthest free cell, a room's middle, whose door the ring cannot see: the
    # corridor's junction in front of a door.
    at = (world.start.x, world.start.y)
    assert min(math.dist(at, (5.0, 1.116)), math.dist(at, CORRIDOR_JUNCTION)) < 0.05, at
    rep = report(explore(str(path), 1, "paper", 3000.0, progress=False), str(path), 1, "paper")
    assert rep["complete"] and rep["false_merges"] == 0

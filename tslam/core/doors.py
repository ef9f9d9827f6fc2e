"""The tracer's rules at doors: into a room whose junction behind the door no sweep can show,
and out through a door the ring sees as one obstacle from afar.

Past a door in the middle of a long wall the jambs fall inside one beam, the ring merges them,
and the trace law, with no edge to follow, goes left or right by noise. These rules keep the
robot on the door's line instead, stand it where the door's edge meets the room's, and on the
way out steer it between the jambs. Each is a pure function of the tracer's parameters, its
state and the cycle's obstacles.
"""

from __future__ import annotations

import math

from hal.types import Odometry
from tslam.core.frames import TAU, to_robot
from tslam.core.sensing import Obstacle
from tslam.core.tracer_params import TracerParams
from tslam.core.tracer_state import TracerState

# A room's door junction (``room_entry_m``): the door's edge, and the room's two across it,
# square to the way in (the ring's bearings of walls 4 m off swing by a transducer's spacing).
ACROSS = (0.0, 0.5 * math.pi, 1.5 * math.pi)


def past_door(p: TracerParams, s: TracerState, odo: Odometry) -> bool:
    """Whether the robot traced between two obstacles both behind it, the jambs of a door it
    went through, within the last ``room_entry_reach_m`` of travel."""
    return s.behind_m is not None and odo.distance_m - s.behind_m <= p.room_entry_reach_m


def entering(
    p: TracerParams, s: TracerState, obs: list[Obstacle], odo: Odometry
) -> tuple[float, float] | None:
    """The course (robot frame) if access is taking the robot on into a room, straight on
    from the door's edge with the nearest obstacle, the door, behind (``room_entry_m``);
    else None."""
    course = s.tangent
    if p.room_entry_m <= 0.0 or course is None or not s.trail or not obs:
        return None
    # Only past a doorway. Elsewhere, going on straight instead of away from the nearest
    # wall lost fig13's lab edges (seeds 1-48: 33 complete against 39).
    if not past_door(p, s, odo):
        return None
    if obs[0].distance_m < p.room_entry_m:
        return None
    _, x, y = s.trail[-1]
    dx, dy = odo.x_m - x, odo.y_m - y
    gone = math.hypot(dx, dy)
    cos_tol = math.cos(p.room_entry_rad)
    if gone > p.room_entry_reach_m or dx * course[0] + dy * course[1] < gone * cos_tol:
        return None
    cx, cy = to_robot(course, odo)
    b = obs[0].bearing_rad
    if math.cos(b) * cx + math.sin(b) * cy > -cos_tol:
        return None
    return cx, cy


def room_entry(p: TracerParams, s: TracerState, obs: list[Obstacle], odo: Odometry) -> float | None:
    """The bearing back to the door (odometry frame), toward where the robot last traced
    between its jambs, if access on its way into the room (``entering``) has reached the
    junction where the door's edge meets the room's; else None."""
    c = entering(p, s, obs, odo)
    if c is None or obs[1].distance_m < p.room_entry_m:
        return None
    _, x, y = s.trail[-1]
    if math.hypot(odo.x_m - x, odo.y_m - y) < 0.3:
        return None
    b = obs[1].bearing_rad
    if math.cos(b) * c[0] + math.sin(b) * c[1] < math.cos(p.room_entry_rad):
        return None  # the second obstacle is not ahead: another edge
    return math.atan2(y - odo.y_m, x - odo.x_m) % TAU


def jambs_apart(p: TracerParams, obs: list[Obstacle]) -> bool:
    """Whether no two of the three nearest obstacles are closer together than a door is
    wide (``apart_gap_m``). A view between the minima of one cabinet's corner, 11 degrees
    apart 1.2 m off, made fig13's meet points (seeds 1-48: 28 complete against 39)."""
    three = obs[:3]
    for i, a in enumerate(three):
        for b in three[i + 1 :]:
            if math.hypot(a.x_m - b.x_m, a.y_m - b.y_m) < p.apart_gap_m:
                return False
    return True


def door_ahead(
    p: TracerParams, s: TracerState, obs: list[Obstacle], err: float
) -> tuple[float, float] | None:
    """The bearing (robot frame) of the middle between the nearest obstacle either side of
    the way ``err`` off the heading, each within ``door_steer_rad`` of it, and the nearer
    one's distance, if the two are about as far (a door's jambs ahead); else None."""
    sides: dict[bool, Obstacle] = {}
    for o in obs:  # nearest first
        off = (o.bearing_rad - err + math.pi) % TAU - math.pi
        if abs(off) <= p.door_steer_rad:
            sides.setdefault(off > 0.0, o)
    if len(sides) < 2:
        return None
    a, b = sides[True], sides[False]
    if abs(a.distance_m - b.distance_m) > s.sides_pair_m:
        return None
    mid = math.atan2(0.5 * (a.y_m + b.y_m), 0.5 * (a.x_m + b.x_m))
    return mid, min(a.distance_m, b.distance_m)


def way_back(s: TracerState, odo: Odometry) -> float:
    """The bearing (odometry frame) back to the node this edge began at, else to where its
    trail began, or against the trace law's tangent if that is under 0.3 m off.
    The node was homed onto, good to centimetres: over the 1 m edges of a floor of two
    rooms (8 stands) that was within 3.3 degrees of the edge's true bearing, the edge's own
    points by the sonar within 8.2 (about a junction the two nearest walls are often another
    edge's pair) and the trail's start within 5.4."""
    ends = [s.odometer.origin]
    if s.trail:
        ends.append((s.trail[0][1], s.trail[0][2]))
    for end in ends:
        if end is not None and math.hypot(end[0] - odo.x_m, end[1] - odo.y_m) >= 0.3:
            return math.atan2(end[1] - odo.y_m, end[0] - odo.x_m) % TAU
    t = s.tangent or (math.cos(odo.heading_rad), math.sin(odo.heading_rad))
    return math.atan2(-t[1], -t[0]) % TAU

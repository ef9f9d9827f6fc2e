"""Out of a room through its door: from office:1's room meet point 94 at (13.2, 4.24), 2.9 m
below a 1 m door, toward the corridor junction 95 at (13.2, 8.08) above it.

The explorer leaves by the door's own bearing, straight on until the ring sees the edge's two
obstacles straddle the way (``ExplorerParams.own_bearing_until_sides_m``): the jambs, which it
resolves only a metre or so from the door. Some 0.6 m out the wall round the door, 2.2 m ahead
and 17 degrees off the way, and a side wall 2.9 m off straddled it: the robot began tracing
them, the trace law dropped a pair 0.7 m apart, access backed it off the wall, and it traced
into the room's top-left corner (seed 2 of the exploration, at 376 s). A pair that straddles
the way must also be about as far (``TracerParams.sides_paired``).
"""

from __future__ import annotations

import math
from dataclasses import replace

import pytest

from sim_backend.backend import SimBackend
from sim_backend.builtin_worlds import builtin_world
from sim_backend.world import PolygonWorld, StartPose
from tslam.core.explorer import ExplorerParams
from tslam.core.tracer import BoundaryReached, MeetPointReached, Tracer, TracerParams

CORRIDOR = (13.2, 8.08)
ROOM = (13.2, 4.24)


def _out_of_the_room(params: TracerParams, seed: int) -> tuple[str, tuple[float, float]]:
    """Leave the room's meet point up toward the door as the explorer does: the kind of the
    first event more than 0.5 m from the start and the true position there."""
    office = builtin_world("office:1")
    start = StartPose(*ROOM, 0.0)
    world = PolygonWorld("office:1", office.boundary, office.obstacles, start, source="test")
    backend = SimBackend(world, seed=seed)
    tracer = Tracer(backend.limits, params)
    robot = backend.robot
    with backend:
        clock = backend.clock
        tracer.depart(math.pi / 2, backend.odometry(), ExplorerParams().own_bearing_until_sides_m)
        while clock.now() < 200.0:
            odo = backend.odometry()
            twist, events = tracer.step(backend.scan(), odo, backend.status(), clock.now())
            backend.command(twist)
            tp = robot.true_pose()
            for ev in events:
                if isinstance(ev, (MeetPointReached, BoundaryReached)):
                    if math.dist((tp.x, tp.y), ROOM) > 0.5:
                        kind = "meet" if isinstance(ev, MeetPointReached) else "boundary"
                        return kind, (tp.x, tp.y)
            clock.sleep(0.1)
    raise AssertionError("no node within 200 s")

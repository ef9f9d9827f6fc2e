"""The robot homes onto a meet point whose third obstacle the ring does not resolve.

fig13's meet point 0, at (1.5, 3.8), is 1.5 m from the left wall, from the table's corner and
from the cabinet's corner. Seen from there, the cabinet's corner is 45 degrees from the
wall's nearest point: two transducers apart, within the ring's merging of minima, and the
reading between them is as short as either with the sonar's noise. So the ring shows the
corner only now and then. Homing began on one such cycle and gave up on the next, and the
robot traced on to meet point 2 or 1: an edge in the map between two places that have a
junction between them, which no later visit could place. That was the most common wrong
edge in fig1 and fig13 explorations (73 of 331 over 12 runs, stop 27's scratch census).

With ``hold_on`` (a switch up to stop 36, the default since stop 37), homing goes on to its
last estimate when the third echo drops out within ``home_hold_m``, and a sweep that finds the
point elsewhere sends homing to the sweep's estimate rather than the ring's.
"""

from __future__ import annotations

import math

import pytest

from sim_backend.backend import SimBackend
from sim_backend.builtin_worlds import builtin_world
from sim_backend.ground_truth import compute_gvg
from sim_backend.world import PolygonWorld, StartPose
from tests.tracer_paths import GIVING_UP
from tslam.core.tracer import BoundaryReached, MeetPointReached, Tracer, TracerParams

FIG13_MEET0 = (1.5, 3.8)


def first_node(params: TracerParams, seed: int, came_from: int) -> tuple[str, float]:
    """Start 40 % of the way from fig13's meet point ``came_from`` (1 or 2) towards meet
    point 0, heading along the edge; the kind of the first node event and how far from meet
    point 0 the robot was then."""
    fig13 = builtin_world("fig13")
    gvg = compute_gvg(fig13)
    edge = next(e for e in gvg.edges if {e.u, e.v} == {came_from, 0})
    pts = edge.points if edge.u == came_from else edge.points[::-1]
    k = int(len(pts) * 0.4)
    (x0, y0), (x1, y1) = pts[k], pts[k + 1]
    start = StartPose(float(x0), float(y0), math.atan2(y1 - y0, x1 - x0))
    world = PolygonWorld("fig13", fig13.boundary, fig13.obstacles, start, source="test")
    backend = SimBackend(world, seed=seed)
    tracer = Tracer(backend.limits, params)
    with backend:
        clock = backend.clock
        tracer.depart(backend.odometry().heading_rad, backend.odometry())
        while clock.now() < 90.0:
            twist, events = tracer.step(
                backend.scan(), backend.odometry(), backend.status(), clock.now()
            )
            backend.command(twist)
            for ev in events:
                if isinstance(ev, (MeetPointReached, BoundaryReached)):
                    tp = backend.robot.true_pose()
                    kind = "meet" if isinstance(ev, MeetPointReached) else "boundary"
                    return kind, math.dist((tp.x, tp.y), FIG13_MEET0)
            clock.sleep(0.1)
    return "none", math.inf


# Seeds from a scratch loop over 1-8 each way with these calls: giving up, the robot went past
# meet point 0 in seeds 2, 6 and 7 from meet point 1 and 1, 3 and 8 from meet point 2; with
# ``hold_on`` it homed there in all 16.
@pytest.mark.parametrize(("came_from", "seed"), [(1, 2), (1, 6), (2, 1), (2, 3)])
def test_homing_holds_on_through_the_corner_the_ring_loses(came_from, seed):
    kind, off = first_node(TracerParams(), seed, came_from)
    assert kind == "meet" and off < 0.15, (kind, off)


@pytest.mark.parametrize(("came_from", "seed"), [(1, 2), (2, 1)])
def test_giving_up_on_the_lost_echo_traces_past_the_meet_point(came_from, seed):
    kind, off = first_node(GIVING_UP, seed, came_from)
    assert kind == "meet" and off > 1.0, (kind, off)

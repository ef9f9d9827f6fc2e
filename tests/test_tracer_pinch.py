"""An edge that runs into walls nearer than the ring can measure ends there, before the base
touches them (``TracerParams.pinch_touch_rad``, the switch ``touch_pinch``; off by default, as
it costs completed maps: README, stop 59).

The Nomad's ring reads nothing under 0.15 m from a transducer, 0.38 m from the centre: closer
walls read as 0.38 m, and the pinch rule (0.3 m) never fired on them. Where the edge ran
between a desk's side and the wall it stands against, and the corner between them lay between
two beams, the base touched the walls (29 of 240 runs of fig1-fig16, seeds 1-48)."""

from __future__ import annotations

import math

import numpy as np

from hal.interfaces import NOMAD200_LIMITS
from hal.types import DriveStatus, Odometry, SonarScan
from tslam.core.tracer import Behaviour, BoundaryReached, Event, Tracer, TracerParams

CLEAR = DriveStatus(bumper=False, stall=False, motors_on=True, stamp_s=0.0)
TOUCH = math.radians(80.0)


def _scan(now: float, ranges: list[float]) -> SonarScan:
    n = len(ranges)
    yaw = np.arange(n) * 2.0 * np.pi / n
    return SonarScan(
        np.array(ranges), 0.23 * np.cos(yaw), 0.23 * np.sin(yaw), yaw, np.full(n, now),
        0.15, 6.5, 0.22,
    )  # fmt: skip


def _narrowing(touching: bool) -> list[float]:
    """Two walls closing in at +-45 degrees ahead (transducers 2 and 14), nearer than the
    ring measures if ``touching``, else 0.4 m off the centre; nothing dead ahead (the corner
    between two beams)."""
    r = [math.nan] * 16
    r[2] = r[14] = 0.15 if touching else 0.17
    r[3] = r[13] = 0.25
    r[4] = r[12] = 0.4
    return r


def _trace_once(
    params: TracerParams, ranges: list[float], armed: bool = True
) -> tuple[Tracer, list[Event]]:
    """One control cycle tracing straight ahead (+x) between the walls of ``ranges``."""
    tracer = Tracer(NOMAD200_LIMITS, params)
    tracer.s.behaviour = Behaviour.TRACE
    tracer.s.tangent = (1.0, 0.0)
    tracer.s.boundary_armed = armed
    tracer.s.last_seen = 0.0
    _, events = tracer.step(_scan(0.0, ranges), Odometry(0.0, 0.0, 0.0, 0.0, 0.0), CLEAR, 0.0)
    return tracer, events


def test_walls_ahead_nearer_than_the_ring_measures_end_the_edge():
    on, events = _trace_once(TracerParams(pinch_touch_rad=TOUCH), _narrowing(touching=True))
    assert [type(e) for e in events] == [BoundaryReached]
    assert on.behaviour is Behaviour.DEPART  # turned back
    # Without the rule the two read 0.38 m, above the pinch rule's 0.3 m: on it goes.
    off, events = _trace_once(TracerParams(pinch_touch_rad=0.0), _narrowing(touching=True))
    assert events == [] and off.behaviour is Behaviour.TRACE


def test_walls_the_ring_still_measures_do_not_end_the_edge():
    # 0.40 m off, as a 1 m door's jambs are passed just off its middle: no corner seen ahead.
    t, events = _trace_once(TracerParams(pinch_touch_rad=TOUCH), _narrowing(touching=False))
    assert events == [] and t.behaviour is Behaviour.TRACE


def test_walls_touching_only_abeam_or_behind_do_not_end_the_edge():
    # The same walls read from a robot going the other way: they are behind it.
    r = _narrowing(touching=True)
    behind = r[8:] + r[:8]
    t, events = _trace_once(TracerParams(pinch_touch_rad=TOUCH), behind)
    assert events == [] and t.behaviour is Behaviour.TRACE


def test_back_into_the_corner_just_left_the_robot_backs_off_before_touching():
    """Turned back from a boundary, the trace law's way flipped back into the corner (the two
    walls nearly symmetric) before the robot was clear of it, with the boundary rule not re-armed:
    it backs off as from a contact, and the boundary rule is armed again."""
    t, events = _trace_once(TracerParams(pinch_touch_rad=TOUCH), _narrowing(True), armed=False)
    assert events == [] and t.behaviour is Behaviour.BACKOFF
    assert t.s.boundary_armed
    # Away from the two walls ahead, whichever way the base was driving.
    assert t.s.escape is not None and t.s.escape[0] < -0.99
    off, _ = _trace_once(TracerParams(pinch_touch_rad=0.0), _narrowing(True), armed=False)
    assert off.behaviour is Behaviour.TRACE

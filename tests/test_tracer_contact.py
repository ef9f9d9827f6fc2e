"""A contact is escaped away from where the base was going, even after the command that
drove into it was zeroed (fig13 seed 1 stood for 20 minutes backing into a wall behind it)."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from hal.interfaces import NOMAD200_LIMITS
from hal.types import DriveStatus, Odometry, SonarScan
from tests.tracer_paths import STOP41
from tslam.core.tracer import Behaviour, Tracer, TracerParams
from tslam.programs.sim_cmd import explore

CLEAR = DriveStatus(bumper=False, stall=False, motors_on=True, stamp_s=0.0)
PRESSED = DriveStatus(bumper=True, stall=True, motors_on=True, stamp_s=0.0)


def silent_scan(now: float) -> SonarScan:
    n = 16
    yaw = np.linspace(0.0, 2 * np.pi, n, endpoint=False)
    return SonarScan(
        np.full(n, np.nan), 0.2 * np.cos(yaw), 0.2 * np.sin(yaw), yaw, np.full(n, now),
        0.15, 6.5, 0.2,
    )  # fmt: skip


def test_backing_into_something_is_escaped_forwards():
    # Contacts kept as obstacles would have the robot leave the first one behind it.
    tracer = Tracer(NOMAD200_LIMITS, TracerParams(contact_hold_s=0.0))
    odo = Odometry(0.0, 0.0, 0.0, 0.0, 0.0)
    now = 0.0
    tracer.step(silent_scan(now), odo, PRESSED, now)  # touched while driving forwards ...
    first, _ = tracer.step(silent_scan(now), odo, PRESSED, now)
    assert tracer.s.behaviour is Behaviour.BACKOFF and first.v_mps < 0.0  # ... so back off
    # The wall it backs into stops it; the bounded backoff ends, and the base stands.
    while tracer.s.behaviour is Behaviour.BACKOFF:
        now += 0.1
        tracer.step(silent_scan(now), odo, CLEAR, now)
        assert now < 60.0
    stand, _ = tracer.step(silent_scan(now), odo, CLEAR, now)
    assert stand.v_mps == 0.0
    # Still pressed: the way out is forwards, away from what it backed into.
    now += 0.1
    tracer.step(silent_scan(now), odo, PRESSED, now)
    out, _ = tracer.step(silent_scan(now), odo, PRESSED, now)
    assert tracer.s.behaviour is Behaviour.BACKOFF and out.v_mps > 0.0


def test_a_contact_is_kept_as_an_obstacle_ahead_for_contact_hold_s():
    """The ring heard nothing (a convex corner in a gap between beams, fig15's boxes): the
    contact puts a point obstacle 0.25 m ahead of the centre, which stays where it was as the
    robot backs off, and goes after ``contact_hold_s``."""
    tracer = Tracer(NOMAD200_LIMITS, TracerParams(contact_hold_s=60.0))
    tracer.step(silent_scan(0.0), Odometry(1.0, 2.0, math.pi / 2, 0.0, 0.0), PRESSED, 0.0)
    assert [(o.x_m, o.y_m) for o in tracer.obstacles] == []  # seen from the next step on
    backed = Odometry(1.0, 1.8, math.pi / 2, 0.0, 1.0)  # 0.2 m back, facing +y
    tracer.step(silent_scan(1.0), backed, CLEAR, 1.0)
    (o,) = tracer.obstacles
    assert (o.distance_m, o.x_m, o.y_m) == pytest.approx((0.45, 0.45, 0.0))
    assert (o.gx, o.gy) == pytest.approx((-1.0, 0.0))
    tracer.step(silent_scan(61.0), backed, CLEAR, 61.0)
    assert tracer.obstacles == []
    off = Tracer(NOMAD200_LIMITS, TracerParams(contact_hold_s=0.0))  # nothing kept
    off.step(silent_scan(0.0), Odometry(1.0, 2.0, math.pi / 2, 0.0, 0.0), PRESSED, 0.0)
    off.step(silent_scan(1.0), backed, CLEAR, 1.0)
    assert off.obstacles == []


def test_a_contact_is_kept_where_a_transducer_read_its_minimum_range():
    """Touching a wall on its left while driving along it (fig13 seed 5 wedged itself between
    the wall and a contact kept ahead of it, 366 times): the transducer facing the wall reads
    its minimum range, and the contact is kept there, not ahead."""
    tracer = Tracer(NOMAD200_LIMITS, TracerParams(contact_hold_s=60.0))
    scan = silent_scan(0.0)
    scan.ranges_m[4] = 0.15  # the transducer at 90 degrees, 0.2 m off the centre
    tracer.step(scan, Odometry(1.0, 2.0, 0.0, 0.0, 0.0), PRESSED, 0.0)
    ((x, y, _),) = tracer.s.contacts
    assert (x, y) == pytest.approx((1.0, 2.35))


def touching_scan(now: float, *bearings_deg: float) -> SonarScan:
    """A silent ring but for the transducers at ``bearings_deg``, which read their minimum
    range: something nearer than they can measure."""
    scan = silent_scan(now)
    for b in bearings_deg:
        scan.ranges_m[round(b / 22.5) % 16] = scan.min_range_m
    return scan


def test_backing_off_pressed_into_a_corner_steers_away_from_both_walls():
    """fig12 seed 1, drift severe: pinned in the top-left corner, the robot backed into one
    wall and drove into the other for hours, the wheels a degree into the first."""
    tracer = Tracer(NOMAD200_LIMITS, TracerParams(contact_hold_s=0.0))
    odo = Odometry(0.0, 0.0, 0.0, 0.0, 0.0)
    tracer.step(touching_scan(0.0, 0.0), odo, PRESSED, 0.0)  # drove into the wall ahead ...
    back, _ = tracer.step(touching_scan(0.1, 0.0), odo, CLEAR, 0.1)
    assert tracer.s.behaviour is Behaviour.BACKOFF and back.v_mps < 0.0 and back.steer_radps == 0
    # ... and backing off straight is stopped too: walls at 90 and 157.5 degrees touch.
    turn, _ = tracer.step(touching_scan(0.2, 90.0, 157.5), odo, PRESSED, 0.2)
    assert tracer.s.behaviour is Behaviour.BACKOFF
    assert turn.steer_radps < 0.0 and turn.v_mps == 0.0  # wheels turn toward -56 degrees first
    way = math.atan2(-(1.0 + math.sin(math.radians(157.5))), -math.cos(math.radians(157.5)))
    turned = Odometry(0.0, 0.0, way, 0.0, 0.3)
    out, _ = tracer.step(touching_scan(0.3), turned, CLEAR, 0.3)
    assert out.v_mps > 0.0 and abs(out.steer_radps) < 1e-6
    # Out by ``backoff_m`` along the way away, it accesses the graph again.
    d = tracer.p.backoff_m
    away = Odometry(d * math.cos(way), d * math.sin(way), way, 0.0, 1.0)
    tracer.step(silent_scan(4.0), away, CLEAR, 4.0)
    assert tracer.s.behaviour is Behaviour.ACCESS


def test_a_stall_backing_off_with_nothing_at_minimum_range_keeps_backing_straight():
    tracer = Tracer(NOMAD200_LIMITS, TracerParams(contact_hold_s=0.0))
    odo = Odometry(0.0, 0.0, 0.0, 0.0, 0.0)
    tracer.step(silent_scan(0.0), odo, PRESSED, 0.0)
    tracer.step(silent_scan(0.1), odo, CLEAR, 0.1)
    again, _ = tracer.step(silent_scan(0.2), odo, PRESSED, 0.2)
    assert tracer.s.escape is None and again.v_mps < 0.0 and again.steer_radps == 0.0


@pytest.mark.parametrize(("before", "armed"), [(Behaviour.TRACE, True), (Behaviour.ACCESS, False)])
def test_a_contact_while_tracing_arms_the_boundary_rule_again(before, armed):
    """fig16 seed 7 traced into the indent's back wall, closer than the ring reads: backed off
    to 0.45 m, short of re-arming the boundary rule, it traced into the wall again, eleven
    times. Touched while tracing, the edge is taken to end there on the way back in."""
    tracer = Tracer(NOMAD200_LIMITS, TracerParams(contact_hold_s=0.0))
    tracer.s.behaviour = before
    tracer.s.boundary_armed = False
    odo = Odometry(0.0, 0.0, 0.0, 0.0, 0.0)
    tracer.step(silent_scan(0.0), odo, PRESSED, 0.0)
    assert tracer.s.behaviour is Behaviour.BACKOFF
    assert tracer.s.boundary_armed is armed


def test_fig16_seed_7_touches_the_indent_once():
    # The contact re-arms the boundary rule: once is all. With the switch that ends an edge on
    # walls nearer than the ring measures (``touch_pinch``), the indent is never touched.
    run = explore("fig16", 7, "paper", duration_s=150.0, progress=False, tracer_params=STOP41)
    assert run.backend.robot.collisions == 1
    touch = replace(STOP41, pinch_touch_rad=math.radians(80.0))
    run = explore("fig16", 7, "paper", duration_s=150.0, progress=False, tracer_params=touch)
    assert run.backend.robot.collisions == 0


def _touch(tracer: Tracer, odo: Odometry, now: float) -> float:
    """Touch something at ``odo``, then wait out the backoff standing; the time after."""
    tracer.step(silent_scan(now), odo, PRESSED, now)
    while tracer.s.behaviour is Behaviour.BACKOFF:
        now += 0.1
        tracer.step(silent_scan(now), odo, CLEAR, now)
        assert now < 1000.0
    return now + 0.1


def test_a_contact_repeated_in_one_place_is_kept_without_contact_hold():
    """fig1 seed 10: re-accessing away from the wall behind it, the robot drove back into a
    wall's end the ring did not hear, 157 times. The third touch within ``repeat_contact_m``
    is kept as an obstacle for ``repeat_hold_s``; touches elsewhere or long ago are not."""
    params = TracerParams(contact_hold_s=0.0)
    odo = Odometry(1.0, 2.0, math.pi / 2, 0.0, 0.0)
    tracer = Tracer(NOMAD200_LIMITS, params)
    now = _touch(tracer, odo, 0.0)
    now = _touch(tracer, odo, now)
    assert tracer.s.contacts == []  # twice is not yet a loop
    now = _touch(tracer, odo, now)
    assert len(tracer.s.contacts) == 1
    tracer.step(silent_scan(now), odo, CLEAR, now)
    assert [round(o.distance_m, 2) for o in tracer.obstacles] == [0.25]  # ahead: none heard
    later = now + params.repeat_hold_s + 1.0
    tracer.step(silent_scan(later), odo, CLEAR, later)
    assert tracer.obstacles == []
    apart = Tracer(NOMAD200_LIMITS, params)
    t = 0.0
    for k in range(3):
        t = _touch(apart, Odometry(1.0 + 0.5 * k, 2.0, math.pi / 2, 0.0, 0.0), t)
    assert apart.s.contacts == []
    slow = Tracer(NOMAD200_LIMITS, params)
    t = 0.0
    for _ in range(3):
        t = _touch(slow, odo, t) + params.repeat_window_s
    assert slow.s.contacts == []
    never = Tracer(NOMAD200_LIMITS, replace(params, repeat_contacts=0))
    t = 0.0
    for _ in range(4):
        t = _touch(never, odo, t)
    assert never.s.contacts == []

"""The simulated sonar: cone geometry, specular silence, corners, occlusion, noise, timing."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from sim_backend.simulator import INCH, NOMAD_FIRING_ORDER, SimParams, SimRobot
from sim_backend.world import PolygonWorld, StartPose
from tests.conftest import box_world

EXACT = SimParams(sonar_noise=False, drift="none", side_lobe_prob=0.0)


def ring(world, params=EXACT, seed=0):
    return SimRobot(world, params, seed).ring.ranges.copy()


def test_wall_straight_ahead_reads_its_perpendicular_distance():
    r = ring(box_world(12, 6, StartPose(2.0, 3.0, 0.0)))
    # Transducer 0 faces +x from x = 2.23; the wall is at x = 12, beyond range: no echo.
    assert math.isnan(r[0])
    # Transducer 8 faces the wall at x = 0 from x = 1.77.
    assert r[8] == pytest.approx(1.77, abs=1e-9)
    # Transducers 4 and 12 face the walls at y = 6 and y = 0 from 0.23 m off the centre line.
    assert r[4] == pytest.approx(2.77, abs=1e-9)
    assert r[12] == pytest.approx(2.77, abs=1e-9)


def test_wall_at_grazing_incidence_is_silent():
    # Transducer 2 points at 45 degrees; the nearest wall's normal is 45 degrees off its axis,
    # and no corner lies in its beam: a smooth wall sends the sound away.
    r = ring(box_world(12, 6, StartPose(2.0, 3.0, 0.0)))
    assert math.isnan(r[2]) and math.isnan(r[14])
    # Transducer 6 (135 degrees) has the room corner (0, 6) in its beam and hears it.
    o6 = (2.0 + 0.23 * math.cos(math.radians(135)), 3.0 + 0.23 * math.sin(math.radians(135)))
    assert r[6] == pytest.approx(math.hypot(o6[0], 6.0 - o6[1]), abs=1e-9)


def test_room_corner_echoes_like_a_reflector():
    # Start on the diagonal of a room corner: transducer 10 (225 degrees) looks straight at it.
    w = box_world(10, 10, StartPose(1.5, 1.5, 0.0))
    r = ring(w)
    ox = 1.5 + 0.23 * math.cos(math.radians(225))
    assert r[10] == pytest.approx(math.hypot(ox, ox), abs=1e-9)


def test_convex_edge_is_heard_only_within_its_range():
    block = [(5.0, 4.0), (6.0, 4.0), (6.0, 5.0), (5.0, 5.0)]
    # Look at the block's corner (5, 4) along the diagonal from the lower left.
    near = box_world(20, 14, StartPose(3.5, 2.5, math.radians(45)), [block])
    far = box_world(20, 14, StartPose(1.0, 0.0 + 0.3, math.radians(45)), [block])
    p = replace(EXACT, convex_echo_range_m=3.0)
    rn = ring(near, p)
    d = math.hypot(1.5, 1.5) - 0.23
    assert rn[0] == pytest.approx(d, abs=1e-9)
    # From further than 3 m the same corner is silent (axis aligned with the corner again).
    th = math.atan2(4.0 - 0.3, 5.0 - 1.0)
    far = box_world(20, 14, StartPose(1.0, 0.3, th), [block])
    assert math.isnan(ring(far, p)[0])


def test_nearer_obstacle_occludes_the_wall_behind():
    pillar = [(4.0, 2.8), (4.4, 2.8), (4.4, 3.2), (4.0, 3.2)]
    r = ring(box_world(8, 6, StartPose(2.0, 3.0, 0.0), [pillar]))
    assert r[0] == pytest.approx(4.0 - 2.23, abs=1e-9)


def test_hidden_corner_is_not_heard_through_a_wall():
    # A wall between the robot and a room corner: the corner must not echo through it.
    wall = [(3.0, -1.0), (3.2, -1.0), (3.2, 2.6), (3.0, 2.6)]
    w = PolygonWorld("hidden", [(0, 0), (6, 0), (6, 6), (0, 6)], [wall], StartPose(1.0, 4.0, 0.0))
    r = ring(w)
    bearing = [math.atan2(0.0 - 4.0, 6.0 - 1.0)]  # lower right room corner, behind the wall
    i = round((bearing[0] % (2 * math.pi)) / (2 * math.pi / 16)) % 16
    assert r[i] != pytest.approx(math.hypot(5.0, 4.0) - 0.23, abs=0.3)


def test_out_of_range_is_no_echo_and_too_close_is_minimum_range():
    r = ring(box_world(20, 3, StartPose(10.0, 0.3 + 0.05, 0.0)))
    assert r[12] == pytest.approx(0.15)  # 0.12 m from the wall: reads the minimum range
    assert math.isnan(r[0])  # 9.77 m to the wall ahead: beyond 6.5 m


def test_inch_quantisation():
    p = replace(EXACT, quantize_inch=True)
    r = ring(box_world(12, 6, StartPose(2.0, 3.0, 0.0)), p)
    assert r[8] == pytest.approx(round(1.77 / INCH) * INCH)
    assert (r[8] / INCH) == pytest.approx(round(r[8] / INCH))


def test_noise_dropouts_and_outliers_follow_their_parameters():
    w = box_world(12, 6, StartPose(2.0, 3.0, 0.0))
    p = replace(SimParams(drift="none"), dropout_prob=0.1, outlier_prob=0.02)
    robot = SimRobot(w, p, seed=42)
    samples = []
    for _ in range(3000):
        robot._fire(8)
        samples.append(robot.ring.ranges[8])
    s = np.array(samples)
    drop = np.isnan(s).mean()
    assert drop == pytest.approx(0.1, abs=0.02)
    good = s[~np.isnan(s)]
    inliers = good[np.abs(good - 1.77) < 0.2]
    outliers = len(good) - len(inliers)
    assert 0.005 < outliers / len(s) < 0.04
    assert inliers.mean() == pytest.approx(1.77, abs=0.005)
    assert inliers.std() == pytest.approx(0.01 + 0.01 * 1.77, rel=0.2)


def test_same_seed_same_readings_different_seed_different_readings():
    w = box_world()
    a = SimRobot(w, SimParams(), seed=7)
    b = SimRobot(w, SimParams(), seed=7)
    c = SimRobot(w, SimParams(), seed=8)
    for r in (a, b, c):
        r.step(3.0)
    assert np.array_equal(a.ring.ranges, b.ring.ranges, equal_nan=True)
    assert not np.array_equal(a.ring.ranges, c.ring.ranges, equal_nan=True)


def test_ring_fires_in_order_one_transducer_per_interval():
    robot = SimRobot(box_world(), EXACT)
    robot.step(0.96 + 1e-9)
    stamps = robot.ring.stamps
    order = np.array(NOMAD_FIRING_ORDER)
    # After the initial ring at t = 0, the k-th in the firing order fired at (k + 1) * 60 ms,
    # the last one at 0.96 s: a full ring in about one second, as on the real robot.
    assert np.allclose(stamps[order], 0.06 * (np.arange(16) + 1))
    assert robot.ring.fired == 32


def test_side_lobes_return_a_near_wall_beyond_the_main_beam():
    # Turn the robot 20 degrees: transducer 4's axis is 20 degrees off the normal of the wall
    # at y = 4, outside the main beam but inside the side lobes, and the wall is 1.8 m away.
    start = StartPose(5.0, 2.0, math.radians(20.0))
    w = box_world(20, 4, start)
    yaw = math.radians(20.0 + 90.0)
    oy = 2.0 + 0.23 * math.sin(yaw)
    assert math.isnan(ring(w, replace(EXACT, side_lobe_prob=0.0))[4])
    assert ring(w, replace(EXACT, side_lobe_prob=1.0))[4] == pytest.approx(4.0 - oy, abs=1e-9)
    # Beyond the side lobes' range the same geometry is silent.
    far = box_world(20, 8, StartPose(5.0, 2.0, math.radians(20.0)))
    assert math.isnan(ring(far, replace(EXACT, side_lobe_prob=1.0))[4])

"""Synchro-drive physics: limits, contact, the independent turret, determinism, the clock."""

from __future__ import annotations

import math

import numpy as np
import pytest

from hal.types import Twist
from sim_backend.backend import SimBackend
from sim_backend.simulator import SimParams, SimRobot
from sim_backend.world import StartPose
from tests.conftest import box_world

EXACT = SimParams(sonar_noise=False, drift="none", side_lobe_prob=0.0)


def test_acceleration_and_speed_limits():
    robot = SimRobot(box_world(30, 6, StartPose(2.0, 3.0, 0.0)), EXACT)
    lim = EXACT.limits
    robot.set_command(lim.v_mps, 0.0, 0.0)
    robot.step(0.2)
    assert robot.v == pytest.approx(lim.accel_mps2 * 0.2)
    robot.step(5.0)
    assert robot.v == pytest.approx(lim.v_mps)
    ramp = lim.v_mps / lim.accel_mps2
    expected = 0.5 * lim.accel_mps2 * ramp**2 + lim.v_mps * (5.2 - ramp)
    # Trapezoidal integration: exact but for the one step where the ramp ends.
    assert robot.true_pose().x - 2.0 == pytest.approx(expected, abs=5e-4)


def test_turret_turns_independently_of_steering():
    robot = SimRobot(box_world(), EXACT)
    robot.set_command(0.0, 0.3, 0.0)
    robot.step(4.0)
    p = robot.true_pose()
    assert p.theta > 0.5 and p.turret == pytest.approx(0.0)
    # Sonar poses are reported in the robot frame: a turret left behind looks backwards there.
    robot.step(1.0)
    assert robot.ring.yaw_robot[0] == pytest.approx(-robot.true_pose().theta, abs=0.35)


def test_contact_stops_the_robot_and_sets_the_bumper():
    robot = SimRobot(box_world(6, 4, StartPose(3.0, 2.0, 0.0)), EXACT)
    robot.set_command(0.5, 0.0, 0.0)
    robot.step(15.0)
    p = robot.true_pose()
    assert p.x == pytest.approx(6.0 - 0.23, abs=1e-6)
    assert robot.bumper and robot.stall and robot.collisions == 1
    assert robot.v == 0.0 and robot.clearance() >= 0.23 - 1e-9
    # Backing off is allowed and clears the bumper.
    robot.set_command(-0.2, 0.0, 0.0)
    robot.step(2.0)
    assert not robot.bumper and robot.true_pose().x < 5.6


def test_same_seed_and_commands_give_the_same_trajectory():
    def run(seed):
        b = SimBackend(box_world(10, 8, StartPose(2.0, 2.0, 0.3)), SimParams(), seed)
        with b:
            path = []
            for k in range(300):
                b.command(Twist(0.3, 0.4 * math.sin(k / 20), 0.0))
                b.clock.sleep(0.1)
                o = b.odometry()
                path.append((o.x_m, o.y_m, o.heading_rad, *b.scan().ranges_m))
            tp = b.robot.true_pose()
            path.append((tp.x, tp.y, tp.theta))
        return path

    a, b, c = run(11), run(11), run(12)
    assert np.array_equal(np.array(a[:-1]), np.array(b[:-1]), equal_nan=True)
    assert a[-1] == b[-1]
    assert not np.array_equal(np.array(a[:-1]), np.array(c[:-1]), equal_nan=True)


def test_odometry_reports_the_dead_reckoned_pose_not_the_truth():
    b = SimBackend(box_world(30, 30, StartPose(15.0, 15.0, 1.0)), SimParams(drift="severe"), 4)
    with b:
        for _ in range(6):
            b.command(Twist(0.4, 0.25, 0.25))
            b.clock.sleep(10.0)
        o = b.odometry()
        tp = b.robot.true_pose()
        wx, wy = b.robot.odometry_to_world(o.x_m, o.y_m)
        # Starts at the origin of its own frame; differs from the truth by the drift only.
        assert 0.0 < math.hypot(wx - tp.x, wy - tp.y) < 0.1 * o.distance_m
        assert o.distance_m == pytest.approx(b.robot.dr.distance)
        assert o.turret_rad - o.heading_rad == pytest.approx(tp.turret - tp.theta, abs=1e-9)


def test_clock_only_moves_when_stepped():
    b = SimBackend(box_world(), EXACT)
    with b:
        t = b.clock.now()
        b.scan()
        b.odometry()
        assert b.clock.now() == t
        b.clock.sleep(0.25)
        assert b.clock.now() == pytest.approx(t + 0.25)


def test_bad_step_is_refused():
    robot = SimRobot(box_world(), EXACT)
    with pytest.raises(ValueError, match="dt must be a finite"):
        robot.step(float("nan"))

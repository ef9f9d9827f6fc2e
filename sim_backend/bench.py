"""Throughput of the simulated sonar ring and of the whole simulator, for ``tslam bench sim``.

Figures, not pass/fail: tests never depend on wall-clock speed.
"""

from __future__ import annotations

import math
import time

import numpy as np

from sim_backend.simulator import SimParams, SimRobot
from sim_backend.world import World, point_segments_distance


def free_poses(world: World, n: int, clearance_m: float, seed: int) -> np.ndarray:
    """``n`` seeded random poses ``(x, y, theta)`` with at least ``clearance_m`` to any wall."""
    rng = np.random.default_rng(seed)
    xmin, ymin, xmax, ymax = world.bounds
    out: list[np.ndarray] = []
    while sum(len(o) for o in out) < n:
        pts = np.column_stack([rng.uniform(xmin, xmax, 4 * n), rng.uniform(ymin, ymax, 4 * n)])
        pts = pts[world.is_free(pts)]
        pts = pts[point_segments_distance(pts, world.segments) >= clearance_m]
        out.append(pts)
    pts = np.vstack(out)[:n]
    return np.column_stack([pts, rng.uniform(-math.pi, math.pi, n)])


def ring_scans_per_s(world: World, n_poses: int = 300, rings_per_pose: int = 10) -> float:
    """Full 16-transducer rings computed per second (cone model, occlusion and noise) at random
    free poses spread over the whole world."""
    robot = SimRobot(world, SimParams(), seed=1)
    poses = free_poses(world, n_poses, robot.p.robot_radius_m, seed=2)
    n = robot.p.n_sonars
    fire = robot._fire
    t0 = time.perf_counter()
    for x, y, th in poses:
        robot.pose.x, robot.pose.y, robot.pose.theta, robot.pose.turret = x, y, th, th
        for _ in range(rings_per_pose):
            for i in range(n):
                fire(i)
    dt = time.perf_counter() - t0
    return n_poses * rings_per_pose / dt


def sim_realtime_factor(world: World, sim_seconds: float = 300.0, rate_hz: float = 10.0) -> float:
    """Simulated seconds per wall second for the whole simulator (physics, collisions, the ring
    firing on schedule, drift) driven with a steady command pattern at ``rate_hz``."""
    robot = SimRobot(world, SimParams(), seed=1)
    period = 1.0 / rate_hz
    steps = int(sim_seconds * rate_hz)
    t0 = time.perf_counter()
    for k in range(steps):
        # Drive, and turn away whenever the bumper or a close wall says so.
        if robot.bumper or robot.clearance() < 0.5:
            robot.set_command(-0.1, 0.6, 0.6)
        else:
            robot.set_command(0.4, 0.15 * math.sin(0.05 * k), 0.15 * math.sin(0.05 * k))
        robot.step(period)
    return sim_seconds / (time.perf_counter() - t0)

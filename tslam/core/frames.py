"""Angles and the robot's two frames: the odometry frame (dead reckoning's x, y, heading) and
the robot frame (x along the heading), for vectors and points."""

from __future__ import annotations

import math

from hal.types import Odometry

TAU = 2.0 * math.pi


def angdiff(a: float, b: float) -> float:
    """The absolute difference of two angles, in [0, pi]."""
    return abs((a - b + math.pi) % TAU - math.pi)


def to_odom(t: tuple[float, float], odo: Odometry) -> tuple[float, float]:
    """A vector in the robot frame turned into the odometry frame."""
    c, s = math.cos(odo.heading_rad), math.sin(odo.heading_rad)
    return c * t[0] - s * t[1], s * t[0] + c * t[1]


def to_robot(t: tuple[float, float], odo: Odometry) -> tuple[float, float]:
    """A vector in the odometry frame turned into the robot frame."""
    c, s = math.cos(odo.heading_rad), math.sin(odo.heading_rad)
    return c * t[0] + s * t[1], -s * t[0] + c * t[1]


def offset(v: tuple[float, float], odo: Odometry) -> tuple[float, float]:
    """The point ``v`` (odometry frame's axes) away from the robot."""
    return odo.x_m + v[0], odo.y_m + v[1]

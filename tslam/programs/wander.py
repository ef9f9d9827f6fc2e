"""A reactive wanderer over the hal: the simulator's demonstration driver until the
exploration arbiter lands. It heads for open space, slows near walls and turns in place when
blocked, keeping the turret aligned with the direction of travel."""

from __future__ import annotations

import math

import numpy as np

from hal.interfaces import DriveLimits
from hal.types import SonarScan, Twist


def wander_step(scan: SonarScan, limits: DriveLimits, turret_offset_rad: float) -> Twist:
    """One control step from the latest scan; ``turret_offset_rad`` = turret - heading."""
    open_range = np.where(scan.echo, scan.ranges_m, scan.max_range_m)
    # Bearing of each transducer relative to the direction of travel.
    rel = np.angle(np.exp(1j * scan.yaw_rad))
    front = np.abs(rel) < math.radians(35.0)
    front_clear = float(open_range[front].min()) if front.any() else 0.0
    # Prefer open directions, mildly prefer straight ahead so the path is not jittery.
    score = open_range * (0.6 + 0.4 * np.cos(rel))
    target = float(rel[int(np.argmax(score))])
    align = -turret_offset_rad  # steer the turret back onto the heading
    if front_clear < 0.45:
        w = math.copysign(limits.steer_radps, target if target != 0 else 1.0)
        return Twist(0.0, w, w + align)
    v = min(limits.v_mps, 0.35 * (front_clear - 0.35))
    w = max(-limits.steer_radps, min(limits.steer_radps, 1.2 * target))
    return Twist(max(0.0, v), w, w + align)

"""A reactive wanderer over the hal: the simulator's demonstration driver until the
exploration arbiter lands. It heads for open space, slows near walls, turns in place when
blocked and backs away when its bumper is pressed (walls at grazing incidence are silent to
sonar, so the bumper is the last word), keeping the turret aligned with its heading."""

from __future__ import annotations

import math

import numpy as np

from hal.interfaces import DriveLimits
from hal.types import DriveStatus, SonarScan, Twist


class Wanderer:
    """Stateful only for its escape manoeuvre; time comes from the caller."""

    def __init__(self, limits: DriveLimits) -> None:
        self.limits = limits
        self._escape_until = -math.inf
        self._escape_turn = 1.0

    def step(
        self, scan: SonarScan, status: DriveStatus, turret_offset_rad: float, now_s: float
    ) -> Twist:
        """One control step; ``turret_offset_rad`` is turret minus heading."""
        lim = self.limits
        align = -turret_offset_rad  # steer the turret back onto the heading
        open_range = np.where(scan.echo, scan.ranges_m, scan.max_range_m)
        rel = np.angle(np.exp(1j * scan.yaw_rad))  # bearing relative to the heading
        if status.bumper or status.stall:
            # Turn away from the side that looks more blocked; alternate when undecided.
            left = open_range[(rel > 0) & (rel < math.pi)].mean()
            right = open_range[(rel < 0) & (rel > -math.pi)].mean()
            self._escape_turn = 1.0 if left >= right else -1.0
            self._escape_until = now_s + 1.5
        if now_s < self._escape_until:
            w = self._escape_turn * lim.steer_radps
            return Twist(-0.1, w, w + align)
        front = np.abs(rel) < math.radians(35.0)
        front_clear = float(open_range[front].min()) if front.any() else 0.0
        # Prefer open directions, mildly prefer straight ahead so the path is not jittery.
        score = open_range * (0.6 + 0.4 * np.cos(rel))
        target = float(rel[int(np.argmax(score))])
        if front_clear < 0.45:
            w = math.copysign(lim.steer_radps, target if target != 0 else 1.0)
            return Twist(0.0, w, w + align)
        v = min(lim.v_mps, 0.35 * (front_clear - 0.35))
        w = max(-lim.steer_radps, min(lim.steer_radps, 1.2 * target))
        return Twist(max(0.0, v), w, w + align)

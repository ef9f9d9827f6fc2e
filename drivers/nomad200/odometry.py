"""Dead reckoning as the hal wants it, from the configuration the robot reports.

The robot reports its steering and turret angles modulo a full turn (0-3599 tenths of a degree)
and no odometer. The hal's ``Odometry`` has continuous angles and a total path length, so this
tracker unwraps each angle to the turn nearest where the last angle and the reported rate put it
(so a slow poll during a fast turn is still unwrapped right) and adds up the distance between
successive reported positions.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from drivers.nomad200.state import State
from drivers.nomad200.units import tenth_deg_to_rad, tenth_inch_to_m

TURN = 3600  # tenths of a degree


def _unwrap(last: float | None, raw: int, rate: int | None, dt: float) -> float:
    """``raw`` (tenths of a degree, any turn) moved to the turn nearest the predicted angle."""
    raw %= TURN
    if last is None:
        return raw - TURN if raw > TURN // 2 else raw
    predicted = last + (rate or 0) * max(dt, 0.0)
    return raw + TURN * round((predicted - raw) / TURN)


@dataclass
class Pose:
    x_m: float
    y_m: float
    heading_rad: float
    turret_rad: float
    distance_m: float
    stamp_s: float


class OdometryTracker:
    def __init__(self) -> None:
        self._steer: float | None = None  # unwrapped, tenths of a degree
        self._turret: float | None = None
        self._xy: tuple[int, int] | None = None
        self._t = 0.0
        self.distance_m = 0.0
        self.pose: Pose | None = None

    def update(self, state: State, stamp_s: float) -> Pose:
        """Take one state reply (with x, y, steer, turret and their rates) stamped ``stamp_s``."""
        if state.x is None or state.y is None or state.steer is None or state.turret is None:
            raise ValueError("the state mask must include x, y, steer and turret")
        dt = stamp_s - self._t
        self._steer = _unwrap(self._steer, state.steer, state.vel_steer, dt)
        self._turret = _unwrap(self._turret, state.turret, state.vel_turret, dt)
        if self._xy is not None:
            dx, dy = state.x - self._xy[0], state.y - self._xy[1]
            self.distance_m += tenth_inch_to_m(math.hypot(dx, dy))
        self._xy = (state.x, state.y)
        self._t = stamp_s
        self.pose = Pose(
            x_m=tenth_inch_to_m(state.x),
            y_m=tenth_inch_to_m(state.y),
            heading_rad=tenth_deg_to_rad(self._steer),
            turret_rad=tenth_deg_to_rad(self._turret),
            distance_m=self.distance_m,
            stamp_s=stamp_s,
        )
        return self.pose

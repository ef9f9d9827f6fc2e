"""The Nomad 200's own motion control, on top of the simulated robot's velocity commands.

The simulator takes velocities; the robot's controller also does position moves (``pr``,
``pa``), a motion watchdog (``conf_tm``), speed caps (``sp``) and reports its pose in a frame
the host may redefine (``dp``, ``da``, ``zr``). This module keeps those, in SI units; the
emulator converts at the wire.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

from sim_backend.simulator import SimRobot

AXES = ("trans", "steer", "turret")
#: Position moves end within these (1/10 inch, 1/10 degree): the wire's resolution.
_TOLERANCE = (0.00254, math.radians(0.1), math.radians(0.1))
_STILL = (1e-4, math.radians(0.01), math.radians(0.01))


@dataclass
class Reported:
    """The pose the robot reports: its dead reckoning in the frame the host defined."""

    x: float
    y: float
    steer: float
    turret: float


class Controller:
    """Position moves, speed caps and the watchdog of one robot."""

    def __init__(self, robot: SimRobot) -> None:
        self.robot = robot
        lim = robot.p.limits
        self.speed = [lim.v_mps, lim.steer_radps, lim.turret_radps]
        self.moves: dict[int, float] = {}  # axis -> target, in axis position units
        self.motion_timeout_s = 0.0
        self.deadline = math.inf
        # The reported frame: a rotation and shift of the dead reckoning, set by dp/da/zr.
        self._rot = 0.0
        self._tx = 0.0
        self._ty = 0.0
        self._turret_shift = 0.0
        dr = robot.dr
        self._last_xy = (dr.x, dr.y)
        self.trans_pos = 0.0  # signed distance travelled: the translation axis's position

    # ------------------------------------------------------------------ reported pose
    def reported(self) -> Reported:
        r = self.robot
        dr = r.dr
        c, s = math.cos(self._rot), math.sin(self._rot)
        return Reported(
            x=self._tx + c * dr.x - s * dr.y,
            y=self._ty + s * dr.x + c * dr.y,
            steer=dr.heading + self._rot,
            turret=r.pose.turret + dr.heading_offset + self._rot + self._turret_shift,
        )

    def define_position(self, x: float, y: float) -> None:
        dr = self.robot.dr
        c, s = math.cos(self._rot), math.sin(self._rot)
        self._tx = x - (c * dr.x - s * dr.y)
        self._ty = y - (s * dr.x + c * dr.y)

    def define_angles(self, steer: float, turret: float) -> None:
        now = self.reported()
        self._rot = steer - self.robot.dr.heading
        self.define_position(now.x, now.y)
        self._turret_shift += turret - self.reported().turret

    def axis_position(self, axis: int) -> float:
        pose = self.reported()
        return (self.trans_pos, pose.steer, pose.turret)[axis]

    def velocity(self, axis: int) -> float:
        r = self.robot
        return (r.v, r.w, r.wt)[axis]

    # ------------------------------------------------------------------ commands
    def arm_watchdog(self) -> None:
        if self.motion_timeout_s > 0:
            self.deadline = self.robot.t + self.motion_timeout_s

    def set_velocity(self, axis: int, value: float) -> None:
        self.moves.pop(axis, None)
        cmd = [self.robot.cmd_v, self.robot.cmd_w, self.robot.cmd_wt]
        cap = self.speed[axis]
        cmd[axis] = max(-cap, min(cap, value))
        self.robot.set_command(*cmd)
        self.robot.motors_on = True

    def move_to(self, axis: int, target: float) -> None:
        self.moves[axis] = target
        self.robot.motors_on = True

    def set_acceleration(self, axis: int, value: float) -> None:
        lim = self.robot.p.limits
        field = ("accel_mps2", "steer_accel_radps2", "turret_accel_radps2")[axis]
        self.robot.p = replace(self.robot.p, limits=replace(lim, **{field: value}))

    def stop(self) -> None:
        self.moves.clear()
        self.robot.stop()
        self.deadline = math.inf

    def stopped(self, axes: tuple[bool, bool, bool]) -> bool:
        cmd = (self.robot.cmd_v, self.robot.cmd_w, self.robot.cmd_wt)
        return all(
            not want or (k not in self.moves and cmd[k] == 0 and abs(self.velocity(k)) < _STILL[k])
            for k, want in enumerate(axes)
        )

    # ------------------------------------------------------------------ time passing
    @property
    def busy(self) -> bool:
        """True while a position move needs the controller at every physics step."""
        return bool(self.moves)

    def after_step(self) -> None:
        """Bookkeeping once the simulation has advanced: odometer, watchdog, moves."""
        r = self.robot
        x, y = r.dr.x, r.dr.y
        d = math.hypot(x - self._last_xy[0], y - self._last_xy[1])
        self.trans_pos += d if r.v >= 0 else -d
        self._last_xy = (x, y)
        if r.t >= self.deadline - 1e-9:
            self.stop()  # conf_tm: no motion command in time
        self._drive_moves()

    def _drive_moves(self) -> None:
        if not self.moves:
            return
        r = self.robot
        cmd = [r.cmd_v, r.cmd_w, r.cmd_wt]
        lim = r.p.limits
        accel = (lim.accel_mps2, lim.steer_accel_radps2, lim.turret_accel_radps2)
        for axis, target in list(self.moves.items()):
            remaining = target - self.axis_position(axis)
            if abs(remaining) < _TOLERANCE[axis]:
                del self.moves[axis]
                cmd[axis] = 0.0
                continue
            # As fast as the axis may go, but slow enough to stop at the target: the speed v
            # with v h + v^2 / 2a = remaining, as the command takes effect a step h late.
            a, h = accel[axis], r.p.physics_dt_s
            braking = math.sqrt((a * h) ** 2 + 2.0 * a * abs(remaining)) - a * h
            speed = min(self.speed[axis], braking)
            cmd[axis] = math.copysign(speed, remaining)
        r.set_command(*cmd)

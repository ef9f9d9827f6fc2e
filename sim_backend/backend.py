"""The simulator behind the hal: ``sim://WORLD?seed=S&drift=paper``.

Options (all optional except the world): ``target`` or ``world`` (a built-in name or a world
file), ``seed`` (int), ``drift`` (none|paper|severe), ``beam_deg`` (half beam width),
``noise`` (sonar noise on or off), ``dropout``, ``outliers``, ``side_lobes`` (probability
a side lobe returns a near wall), ``quantize_inch``,
``fire_interval_s``, ``physics_dt_s``.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import replace
from typing import Any

import numpy as np

from hal.config import Options
from hal.errors import ConfigurationError
from hal.interfaces import Drive, DriveLimits, Encoders, SonarRing
from hal.types import DriveStatus, Odometry, SonarScan, Twist
from sim_backend.odometry_model import DRIFT_LEVELS
from sim_backend.simulator import SimParams, SimRobot
from sim_backend.world import World, WorldError
from sim_backend.world_files import load_world

#: The range of ``fire_interval_s``: 4 ms a transducer is a ring in 64 ms, as fast as the CAN
#: sonar board fires it.
FIRE_INTERVAL_MIN_S = 0.004
FIRE_INTERVAL_MAX_S = 1.0


class SimClock:
    """Simulated time: ``sleep`` steps the simulator, so loops run as fast as the CPU allows."""

    def __init__(self, robot: SimRobot) -> None:
        self._robot = robot

    def now(self) -> float:
        return self._robot.t

    def sleep(self, seconds: float) -> None:
        if seconds > 0:
            self._robot.step(seconds)


class SimBackend(Drive, Encoders, SonarRing):
    """A simulated Nomad 200 providing all three interfaces."""

    backend_name = "sim"

    def __init__(self, world: World, params: SimParams | None = None, seed: int = 0) -> None:
        super().__init__()
        self.world = world
        self.params = params or SimParams()
        self.seed = seed
        # The robot exists from the start (its clock must be readable), but nothing moves
        # until the backend is active: the hal refuses commands before that.
        self.robot = SimRobot(world, self.params, seed)
        self.robot.motors_on = False
        self._clock = SimClock(self.robot)

    @classmethod
    def from_config(cls, options: Mapping[str, Any]) -> SimBackend:
        opts = Options("sim", options)
        spec = opts.str("world", opts.str("target", "fig1"))
        seed = opts.int("seed", 0, lo=0)
        p = SimParams()
        p = replace(
            p,
            drift=opts.choice("drift", DRIFT_LEVELS, "paper"),
            half_beam_rad=math.radians(opts.float("beam_deg", 12.5, lo=1.0, hi=60.0)),
            sonar_noise=opts.bool("noise", True),
            dropout_prob=opts.float("dropout", p.dropout_prob, lo=0.0, hi=1.0),
            outlier_prob=opts.float("outliers", p.outlier_prob, lo=0.0, hi=1.0),
            side_lobe_prob=opts.float("side_lobes", p.side_lobe_prob, lo=0.0, hi=1.0),
            quantize_inch=opts.bool("quantize_inch", False),
            fire_interval_s=opts.float(
                "fire_interval_s", p.fire_interval_s, lo=FIRE_INTERVAL_MIN_S, hi=FIRE_INTERVAL_MAX_S
            ),
            physics_dt_s=opts.float("physics_dt_s", p.physics_dt_s, lo=0.001, hi=0.2),
        )
        opts.finish()
        try:
            world = load_world(spec)
            return cls(world, p, seed)
        except WorldError as exc:
            raise ConfigurationError(f"sim: {exc}") from None

    # ------------------------------------------------------------------ Backend
    @property
    def clock(self) -> SimClock:
        return self._clock

    @property
    def limits(self) -> DriveLimits:
        return self.params.limits

    @property
    def n_transducers(self) -> int:
        return self.params.n_sonars

    def _on_activate(self) -> None:
        self.robot.motors_on = True

    def _on_deactivate(self) -> None:
        self.robot.motors_on = False

    # ------------------------------------------------------------------ Drive
    def _command(self, twist: Twist) -> None:
        self.robot.set_command(twist.v_mps, twist.steer_radps, twist.turret_radps)

    def _stop(self) -> None:
        self.robot.stop()

    def _status(self) -> DriveStatus:
        r = self.robot
        return DriveStatus(bumper=r.bumper, stall=r.stall, motors_on=r.motors_on, stamp_s=r.t)

    # ------------------------------------------------------------------ Encoders
    def _odometry(self) -> Odometry:
        r = self.robot
        dr = r.dr
        return Odometry(
            x_m=dr.x,
            y_m=dr.y,
            heading_rad=dr.heading,
            turret_rad=r.pose.turret + dr.heading_offset,
            stamp_s=r.t,
            distance_m=dr.distance,
        )

    # ------------------------------------------------------------------ SonarRing
    def _scan(self) -> SonarScan:
        p = self.params
        ring = self.robot.ring
        yaw = ring.yaw_robot.copy()
        return SonarScan(
            ranges_m=ring.ranges.copy(),
            x_m=p.ring_radius_m * np.cos(yaw),
            y_m=p.ring_radius_m * np.sin(yaw),
            yaw_rad=yaw,
            stamps_s=ring.stamps.copy(),
            min_range_m=p.min_range_m,
            max_range_m=p.max_range_m,
            half_beam_rad=p.half_beam_rad,
        )

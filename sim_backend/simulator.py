"""The simulated Nomad 200: synchro-drive physics, a sonar ring fired in order, drifting
encoders, all on a stepped clock.

Time passes only in ``step``; nothing reads the host clock, so a run is a pure function of the
world, the parameters, the seed and the commands. The true pose is for tests and scoring:
the hal backend never exposes it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from hal.interfaces import NOMAD200_LIMITS, DriveLimits
from sim_backend.kernels import min_distance, points_near, segments_near, sonar_echo
from sim_backend.odometry_model import DeadReckoning, DriftParams
from sim_backend.world import World

#: The firing order commonly configured on a Nomad 200 ring (opposite sides alternate).
NOMAD_FIRING_ORDER = (0, 2, 15, 1, 14, 3, 13, 4, 12, 5, 11, 6, 10, 7, 9, 8)
INCH = 0.0254


@dataclass(frozen=True)
class SimParams:
    """Everything physical about the simulated robot, in SI units."""

    robot_radius_m: float = 0.23
    ring_radius_m: float = 0.23
    n_sonars: int = 16
    half_beam_rad: float = math.radians(12.5)
    min_range_m: float = 0.15
    max_range_m: float = 6.5
    #: Convex obstacle edges diffract a weak echo, heard only this far.
    convex_echo_range_m: float = 4.0
    #: Side lobes: a wall whose normal is within this angle of the axis (beyond the main
    #: beam) echoes with ``side_lobe_prob``, up to ``side_lobe_range_m``.
    side_lobe_rad: float = math.radians(30.0)
    side_lobe_range_m: float = 2.5
    side_lobe_prob: float = 0.5
    range_noise_m: float = 0.01
    range_noise_rel: float = 0.01
    dropout_prob: float = 0.02
    outlier_prob: float = 0.005
    quantize_inch: bool = False
    #: 15 x 4 ms per transducer, as the ring is usually configured: a full ring in 0.96 s.
    fire_interval_s: float = 0.060
    firing_order: tuple[int, ...] = NOMAD_FIRING_ORDER
    limits: DriveLimits = NOMAD200_LIMITS
    physics_dt_s: float = 0.05
    drift: str = "paper"
    sonar_noise: bool = True

    def __post_init__(self) -> None:
        if sorted(self.firing_order) != sorted(set(self.firing_order)) or not all(
            0 <= i < self.n_sonars for i in self.firing_order
        ):
            raise ValueError(f"firing_order must list distinct transducers 0..{self.n_sonars - 1}")
        if not self.firing_order:
            raise ValueError("firing_order must name at least one transducer")
        if self.fire_interval_s <= 0 or self.physics_dt_s <= 0:
            raise ValueError("fire_interval_s and physics_dt_s must be positive")
        if not 0 < self.min_range_m < self.max_range_m:
            raise ValueError("need 0 < min_range_m < max_range_m")
        DriftParams.level(self.drift)


@dataclass
class TruePose:
    x: float
    y: float
    theta: float
    turret: float


@dataclass
class _Ring:
    ranges: np.ndarray
    yaw_robot: np.ndarray
    stamps: np.ndarray
    fired: int = 0  # transducer firings since the start
    next_fire_t: float = 0.0
    order_pos: int = 0


class SimRobot:
    """A Nomad 200 in a world. Construct, then ``step`` to let time pass."""

    def __init__(self, world: World, params: SimParams | None = None, seed: int = 0) -> None:
        self.world = world
        self.p = params or SimParams()
        world.check_start(self.p.robot_radius_m)
        self.seed = seed
        sonar_seq, odo_seq = np.random.SeedSequence(seed).spawn(2)
        self._sonar_rng = np.random.default_rng(sonar_seq)
        s = world.start
        self.t = 0.0
        self.pose = TruePose(s.x, s.y, s.theta, s.theta)
        self.v = self.w = self.wt = 0.0
        self.cmd_v = self.cmd_w = self.cmd_wt = 0.0
        self.bumper = False
        self.stall = False
        self.motors_on = True
        self.collisions = 0
        self.dr = DeadReckoning(
            s.theta, DriftParams.level(self.p.drift), np.random.default_rng(odo_seq)
        )
        self._segs = np.ascontiguousarray(world.segments, dtype=np.float64)
        self._corners = np.ascontiguousarray(world.corners, dtype=np.float64)
        self._convex = np.ascontiguousarray(world.corner_convex, dtype=np.bool_)
        self._local_center = (math.inf, math.inf)
        self._refresh_margin = 0.5
        self._seg_idx = np.zeros(0, dtype=np.int64)
        self._corner_idx = np.zeros(0, dtype=np.int64)
        n = self.p.n_sonars
        self._angles = np.arange(n) * (2.0 * math.pi / n)
        self.ring = _Ring(np.full(n, np.nan), self._angles.copy(), np.zeros(n))
        # The ring is already running when the simulation starts: one full ring at t = 0.
        for i in range(n):
            self._fire(i)
        self.ring.next_fire_t = self.p.fire_interval_s
        self._clearance = self._distance(s.x, s.y)

    # ----------------------------------------------------------------- commands
    def set_command(self, v: float, w: float, wt: float) -> None:
        """Commanded velocities (m/s, rad/s, rad/s); the caller clamps them to the limits."""
        self.cmd_v, self.cmd_w, self.cmd_wt = v, w, wt
        self.stall = False

    def stop(self) -> None:
        self.set_command(0.0, 0.0, 0.0)

    # ----------------------------------------------------------------- time
    def step(self, dt: float) -> None:
        """Advance the simulation by ``dt`` seconds."""
        if not (dt >= 0 and math.isfinite(dt)):
            raise ValueError(f"dt must be a finite non-negative number of seconds, got {dt}")
        t_end = self.t + dt
        ring = self.ring
        while True:
            if ring.next_fire_t <= self.t + 1e-12:
                order = self.p.firing_order
                self._fire(order[ring.order_pos])
                ring.order_pos = (ring.order_pos + 1) % len(order)
                ring.next_fire_t += self.p.fire_interval_s
                continue
            if self.t >= t_end - 1e-12:
                break
            h = min(t_end - self.t, self.p.physics_dt_s, ring.next_fire_t - self.t)
            self._physics(h)
        self.t = max(self.t, t_end)

    def _physics(self, h: float) -> None:
        lim = self.p.limits
        v0, w0, wt0 = self.v, self.w, self.wt
        self.v = _approach(v0, self.cmd_v, lim.accel_mps2 * h)
        self.w = _approach(w0, self.cmd_w, lim.steer_accel_radps2 * h)
        self.wt = _approach(wt0, self.cmd_wt, lim.turret_accel_radps2 * h)
        ds = 0.5 * (v0 + self.v) * h
        dth = 0.5 * (w0 + self.w) * h
        dtu = 0.5 * (wt0 + self.wt) * h
        pose = self.pose
        if ds != 0.0:
            mid = pose.theta + 0.5 * dth
            cx, cy = math.cos(mid), math.sin(mid)
            nx, ny = pose.x + ds * cx, pose.y + ds * cy
            clear = self._distance(nx, ny)
            r = self.p.robot_radius_m
            if clear < r and clear < self._clearance:
                # Contact: advance only as far as the robot fits, then stop like the real
                # base does when its bumper ring is pressed.
                lo, hi = 0.0, 1.0
                for _ in range(20):
                    mid_f = 0.5 * (lo + hi)
                    if self._distance(pose.x + mid_f * ds * cx, pose.y + mid_f * ds * cy) >= r:
                        lo = mid_f
                    else:
                        hi = mid_f
                ds *= lo
                nx, ny = pose.x + ds * cx, pose.y + ds * cy
                clear = self._distance(nx, ny)
                self.stall = self.cmd_v != 0.0
                self.v = self.cmd_v = 0.0
                if not self.bumper:
                    self.collisions += 1  # a new contact, not one still being pushed on
                self.bumper = True
            else:
                self.bumper = clear < r + 1e-3
            pose.x, pose.y = nx, ny
            self._clearance = clear
        self.dr.update(ds, dth)
        pose.theta += dth
        pose.turret += dtu
        self.t += h

    # ----------------------------------------------------------------- sensing
    def _refresh_local(self) -> None:
        x, y = self.pose.x, self.pose.y
        cx, cy = self._local_center
        if (x - cx) ** 2 + (y - cy) ** 2 <= self._refresh_margin**2:
            return
        radius = self.p.ring_radius_m + self.p.max_range_m + self._refresh_margin + 0.05
        self._seg_idx = segments_near(self._segs, x, y, radius)
        self._corner_idx = points_near(self._corners, x, y, radius)
        self._local_center = (x, y)

    def _distance(self, x: float, y: float) -> float:
        self._refresh_local()
        return min_distance(x, y, self._segs, self._seg_idx)

    def _fire(self, i: int) -> None:
        p = self.p
        pose = self.pose
        self._refresh_local()
        yaw = pose.turret + self._angles[i]
        ox = pose.x + p.ring_radius_m * math.cos(yaw)
        oy = pose.y + p.ring_radius_m * math.sin(yaw)
        r, side = sonar_echo(
            ox, oy, yaw, p.half_beam_rad, p.max_range_m, p.convex_echo_range_m,
            p.side_lobe_rad, p.side_lobe_range_m,
            self._segs, self._seg_idx, self._corners, self._convex, self._corner_idx,
        )  # fmt: skip
        if side < r and self._sonar_rng.random() < p.side_lobe_prob:
            r = side
        ring = self.ring
        ring.ranges[i] = self._measure(r)
        ring.yaw_robot[i] = pose.turret - pose.theta + self._angles[i]
        ring.stamps[i] = self.t
        ring.fired += 1

    def _measure(self, r: float) -> float:
        """Turn a true echo range (inf: none) into what the transducer reports (NaN: none)."""
        p = self.p
        if p.sonar_noise:
            u = self._sonar_rng.random()
            if u < p.outlier_prob:
                # Multipath and crosstalk: a reading unrelated to the geometry.
                r = p.min_range_m + self._sonar_rng.random() * (p.max_range_m - p.min_range_m)
            elif not math.isfinite(r) or u < p.outlier_prob + p.dropout_prob:
                return math.nan  # no echo, or an echo the receiver missed
            else:
                r += self._sonar_rng.normal(0.0, p.range_noise_m + p.range_noise_rel * r)
        elif not math.isfinite(r):
            return math.nan
        if p.quantize_inch:
            r = round(r / INCH) * INCH
        if r > p.max_range_m:
            return math.nan
        return max(r, p.min_range_m)

    # ----------------------------------------------------------------- for tests and scoring
    def true_pose(self) -> TruePose:
        """Ground truth; never reachable through the hal."""
        return TruePose(self.pose.x, self.pose.y, self.pose.theta, self.pose.turret)

    def clearance(self) -> float:
        """True distance from the robot's centre to the nearest wall."""
        return self._distance(self.pose.x, self.pose.y)

    def odometry_to_world(self, x: float, y: float) -> tuple[float, float]:
        """Where the odometry frame's origin-aligned point would be if encoders were perfect."""
        s = self.world.start
        c, sn = math.cos(s.theta), math.sin(s.theta)
        return s.x + c * x - sn * y, s.y + sn * x + c * y


def _approach(current: float, target: float, max_step: float) -> float:
    if target > current:
        return min(target, current + max_step)
    return max(target, current - max_step)

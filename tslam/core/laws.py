"""The paper's control laws on obstacles (section III-B, III-C), as pure functions.

Vectors are in the robot frame, metres and metres per second. The velocity a law asks for
is a planar vector; ``to_twist`` turns it into synchro-drive commands.

Gains: ``alpha`` (m/s) is the speed along the edge; ``beta`` (1/s) pulls the robot back onto
the edge: a lateral error ``e`` closes at about ``beta * e`` m/s. Stability asks for
``beta / alpha > 1`` in these units (the paper's condition, eq. 1); the defaults, 0.25 m/s
and 0.8 1/s, give 4.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from hal.interfaces import DriveLimits
from hal.types import Twist
from tslam.core.sensing import Obstacle

Vec = tuple[float, float]


def access_velocity(obstacles: Sequence[Obstacle], speed: float) -> Vec:
    """Move away from the closest obstacle (gradient ascent of its distance)."""
    o = obstacles[0]
    return speed * o.gx, speed * o.gy


def equidistant(obstacles: Sequence[Obstacle], count: int, tol_m: float) -> bool:
    """True when the ``count`` closest obstacles are equidistant within ``tol_m``."""
    return (
        len(obstacles) >= count
        and obstacles[count - 1].distance_m - obstacles[0].distance_m <= tol_m
    )


def edge_tangent(o1: Obstacle, o2: Obstacle, previous: Vec | None) -> Vec | None:
    """Unit vector along the GVG edge of ``o1`` and ``o2`` (the null space of grad G), the
    side chosen to continue ``previous``; None where the two gradients coincide."""
    gx, gy = o1.gx - o2.gx, o1.gy - o2.gy
    n = math.hypot(gx, gy)
    if n < 1e-6:
        return None
    tx, ty = -gy / n, gx / n
    if previous is not None and tx * previous[0] + ty * previous[1] < 0:
        tx, ty = -tx, -ty
    return tx, ty


def trace_velocity(
    o1: Obstacle,
    o2: Obstacle,
    previous: Vec | None,
    alpha: float,
    beta: float,
    max_correction: float = 0.15,
) -> tuple[Vec, Vec] | None:
    """Eq. (1): ``alpha Null(grad G) - beta pinv(grad G) G`` with ``G = d1 - d2``.

    Returns the velocity and the tangent used (to keep the direction next step), or None if
    the two obstacles give no edge. The correction is capped at ``max_correction`` m/s.
    """
    t = edge_tangent(o1, o2, previous)
    pull = step_onto_edge(o1, o2, beta)
    if t is None or pull is None:
        return None
    cx, cy = pull
    c = math.hypot(cx, cy)
    if c > max_correction:  # far off the edge, steer back but do not race
        cx, cy = cx * max_correction / c, cy * max_correction / c
    return (alpha * t[0] + cx, alpha * t[1] + cy), t


def step_onto_edge(o1: Obstacle, o2: Obstacle, gain: float = 1.0) -> Vec | None:
    """``-gain pinv(grad G) G`` with ``G = d1 - d2``: with gain 1, the step onto the edge of
    ``o1`` and ``o2`` to first order (moving along -grad G lowers G); with ``beta``, eq. (1)'s
    pull back onto it. None where the two gradients coincide."""
    gx, gy = o1.gx - o2.gx, o1.gy - o2.gy
    n2 = gx * gx + gy * gy
    if n2 < 1e-12:  # as edge_tangent: |grad G| below 1e-6
        return None
    g = o1.distance_m - o2.distance_m
    return -gain * g * gx / n2, -gain * g * gy / n2


def circumcentre(a: Obstacle, b: Obstacle, c: Obstacle) -> Vec | None:
    """Centre of the circle through the three closest points: where homing heads (III-C)."""
    ax, ay, bx, by, cx, cy = a.x_m, a.y_m, b.x_m, b.y_m, c.x_m, c.y_m
    d = 2.0 * (ax * (by - cy) + bx * (cy - ay) + cx * (ay - by))
    if abs(d) < 1e-9:
        return None
    a2, b2, c2 = ax * ax + ay * ay, bx * bx + by * by, cx * cx + cy * cy
    ux = (a2 * (by - cy) + b2 * (cy - ay) + c2 * (ay - by)) / d
    uy = (a2 * (cx - bx) + b2 * (ax - cx) + c2 * (bx - ax)) / d
    return ux, uy


def homing_velocity(target: Vec, gain: float, max_speed: float) -> Vec:
    """A step toward the meet point estimate, proportional to its distance, capped."""
    dist = math.hypot(*target)
    if dist < 1e-9:
        return 0.0, 0.0
    speed = min(max_speed, gain * dist)
    return speed * target[0] / dist, speed * target[1] / dist


def departure_bearings(obstacles: Sequence[Obstacle]) -> list[float]:
    """Directions of the GVG edges leaving a meet point, robot frame, counter-clockwise.

    Between two obstacles adjacent in bearing, the edge equidistant to them leaves along the
    bisector of the gap between their closest points.
    """
    b = sorted(o.bearing_rad % (2 * math.pi) for o in obstacles)
    out = []
    for i, lo in enumerate(b):
        hi = b[(i + 1) % len(b)] + (2 * math.pi if i + 1 == len(b) else 0.0)
        out.append((lo + 0.5 * (hi - lo)) % (2 * math.pi))
    return sorted(out)


def to_twist(
    v: Vec, limits: DriveLimits, steer_gain: float = 1.5, reverse_ok: bool = False
) -> Twist:
    """Synchro-drive command for a desired planar velocity ``v`` (robot frame).

    The wheels steer toward ``v`` no faster than they can stop in time (the steering
    decelerates at a bounded rate, so a plain proportional command overshoots and spins),
    and translate with the component of ``v`` along the heading, nothing while badly
    misaligned. The turret holds still: a ring that turns while its transducers fire one at
    a time samples the walls unevenly.
    """
    speed = math.hypot(*v)
    if speed < 1e-6:
        return Twist(0.0, 0.0, 0.0)
    err = math.atan2(v[1], v[0])
    sign = 1.0
    if reverse_ok and abs(err) > math.pi / 2:
        err = math.atan2(-v[1], -v[0])
        sign = -1.0
    w = steer_rate(err, limits, steer_gain)
    along = speed * math.cos(err)
    trans = sign * min(limits.v_mps, max(0.0, along)) if abs(err) < math.radians(45) else 0.0
    return Twist(trans, w, 0.0)


def steer_rate(err: float, limits: DriveLimits, gain: float = 1.5) -> float:
    """Steering rate that closes a heading error ``err`` without overshoot: proportional
    near zero, and never faster than braking at the steering's deceleration allows."""
    brake = math.sqrt(2.0 * limits.steer_accel_radps2 * abs(err))
    return math.copysign(min(gain * abs(err), brake, limits.steer_radps), err)


def _clamp(x: float, lim: float) -> float:
    return max(-lim, min(lim, x))


def seen_from(obstacles: Sequence[Obstacle], c: Vec) -> list[float]:
    """Each obstacle's distance from the point ``c`` (robot frame), to first order: its
    closest point slides along the wall as the viewpoint moves, so the distance changes by
    the step's component along the gradient (exact for a flat wall)."""
    return [o.distance_m + o.gx * c[0] + o.gy * c[1] for o in obstacles]


def wall_centre(a: Obstacle, b: Obstacle, c: Obstacle) -> Vec | None:
    """The point equidistant to the three obstacles to first order (``seen_from``): where
    their meet point is, from a robot standing off it: its distances to the three then
    spread by up to twice the offset, and the circle through the three closest points is
    centred off the meet point where a closest point has slid along its wall (2 cm at 36 cm
    off). None if the three gradients leave no such point (three parallel walls)."""
    rows = [(o.gx, o.gy, o.distance_m) for o in (a, b, c)]
    # d_i + g_i . x = r for i = 1..3: subtract the first to eliminate r.
    (g0x, g0y, d0), (g1x, g1y, d1), (g2x, g2y, d2) = rows
    m11, m12, r1 = g1x - g0x, g1y - g0y, d0 - d1
    m21, m22, r2 = g2x - g0x, g2y - g0y, d0 - d2
    det = m11 * m22 - m12 * m21
    if abs(det) < 1e-6:
        return None
    return (r1 * m22 - m12 * r2) / det, (m11 * r2 - m21 * r1) / det

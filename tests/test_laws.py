"""The control laws on synthetic obstacles, where the right answer is known."""

from __future__ import annotations

import math

import pytest

from hal.interfaces import NOMAD200_LIMITS
from tslam.core import laws
from tslam.core.sensing import Obstacle


def wall(distance: float, bearing_deg: float) -> Obstacle:
    b = math.radians(bearing_deg)
    return Obstacle(
        distance, distance * math.cos(b), distance * math.sin(b), -math.cos(b), -math.sin(b), b
    )


def test_on_the_edge_the_law_moves_along_it_only():
    (vx, vy), t = laws.trace_velocity(wall(1.0, 90), wall(1.0, -90), (1.0, 0.0), 0.2, 0.8)
    assert (vx, vy) == pytest.approx((0.2, 0.0))
    assert t == pytest.approx((1.0, 0.0))


def test_off_the_edge_the_law_steers_back_and_keeps_its_direction():
    # Closer to the left wall (bearing 90): the correction points right (negative y).
    (vx, vy), t = laws.trace_velocity(wall(0.9, 90), wall(1.1, -90), (-1.0, 0.0), 0.2, 0.8)
    assert vx == pytest.approx(-0.2) and vy == pytest.approx(-0.08)
    assert t == pytest.approx((-1.0, 0.0))  # the previous direction of travel is kept


def test_correction_is_capped():
    (vx, vy), _ = laws.trace_velocity(wall(0.5, 90), wall(3.5, -90), (1.0, 0.0), 0.2, 0.8)
    assert math.hypot(vx - 0.2, vy) == pytest.approx(0.15)


def test_homing_heads_for_the_centre_of_the_three_closest_points():
    c = laws.circumcentre(wall(1.0, 90), wall(1.2, -90), wall(1.1, 0))
    assert c is not None
    # Equidistant to the three points (0, 1), (0, -1.2) and (1.1, 0).
    d = [math.hypot(c[0] - x, c[1] - y) for x, y in [(0, 1.0), (0, -1.2), (1.1, 0)]]
    assert max(d) - min(d) < 1e-9
    v = laws.homing_velocity(c, gain=1.0, max_speed=0.15)
    assert math.hypot(*v) <= 0.15 + 1e-12


def test_departures_bisect_the_gaps_between_obstacles():
    # A T junction seen from its meet point: walls at 90 and 270, a corner at 0? Use three
    # obstacles at 0, 120, 240 degrees: the edges leave at 60, 180, 300.
    deps = laws.departure_bearings([wall(1, 0), wall(1, 120), wall(1, 240)])
    assert [round(math.degrees(d)) for d in deps] == [60, 180, 300]


def test_steering_never_asks_more_than_it_can_brake_from():
    lim = NOMAD200_LIMITS
    for err in (0.01, 0.1, 0.5, 2.0):
        w = laws.steer_rate(err, lim)
        assert 0 < w <= lim.steer_radps
        assert w**2 <= 2 * lim.steer_accel_radps2 * err + 1e-12


def test_to_twist_translates_only_when_facing_the_velocity():
    lim = NOMAD200_LIMITS
    ahead = laws.to_twist((0.2, 0.0), lim)
    assert ahead.v_mps == pytest.approx(0.2) and ahead.steer_radps == 0.0
    side = laws.to_twist((0.0, 0.2), lim)
    assert side.v_mps == 0.0 and side.steer_radps > 0
    back = laws.to_twist((-0.2, 0.0), lim, reverse_ok=True)
    assert back.v_mps == pytest.approx(-0.2)


def _flat_walls(meet: tuple[float, float], clearance: float, bearings_deg: list[float]):
    """Obstacles seen from the origin of flat walls ``clearance`` from the point ``meet``,
    their normals at ``bearings_deg``."""
    out = []
    for b in bearings_deg:
        u = (math.cos(math.radians(b)), math.sin(math.radians(b)))
        d = clearance + meet[0] * u[0] + meet[1] * u[1]
        out.append(Obstacle(d, d * u[0], d * u[1], -u[0], -u[1], math.radians(b)))
    return out


def test_the_wall_centre_is_the_meet_point_from_a_few_centimetres_off():
    # The robot stands 6 cm off a meet point of three flat walls.
    obs = _flat_walls((0.05, -0.03), 1.25, [90.0, 210.0, 330.0])
    c = laws.wall_centre(*obs)
    assert c == pytest.approx((0.05, -0.03), abs=1e-9)
    assert laws.seen_from(obs, c) == pytest.approx([1.25, 1.25, 1.25])
    # 36 cm off, the circle through the three closest points is centred 2 cm from it.
    far = _flat_walls((0.3, -0.2), 1.25, [90.0, 210.0, 330.0])
    assert laws.wall_centre(*far) == pytest.approx((0.3, -0.2), abs=1e-9)
    assert math.dist(laws.circumcentre(*far), (0.3, -0.2)) > 0.015
    # Seen from where the robot stands, the three spread by twice its offset or so.
    spread = max(o.distance_m for o in obs) - min(o.distance_m for o in obs)
    assert spread > 0.08


def test_two_parallel_walls_and_a_third_have_a_centre_but_three_parallel_none():
    assert laws.wall_centre(*_flat_walls((0.0, 0.0), 1.0, [90.0, 270.0, 0.0])) == pytest.approx(
        (0.0, 0.0), abs=1e-9
    )
    walls = _flat_walls((0.0, 0.0), 1.0, [90.0, 270.0, 90.0])
    assert laws.wall_centre(*walls) is None

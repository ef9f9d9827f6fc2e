"""Homing close to its point keeps to it when one echo changes the ring's estimate (the
tracer switch ``keep``, off by default).

fig16 seed 5: the robot stood 6 cm off the indent's weak meet point, turning its wheels
toward it; one wall's echo dropped out, and the three obstacles left defined the corridor's
meet point 0.4 m away. Homing went there, and the sweep rejected it.
"""

from __future__ import annotations

import math

import pytest

from hal.interfaces import NOMAD200_LIMITS
from hal.types import Odometry
from tslam.core.sensing import Obstacle
from tslam.core.tracer import Behaviour, Tracer, TracerParams


def _walls_round(cx: float, cy: float, r: float) -> list[Obstacle]:
    """Three obstacles ``r`` from (cx, cy), robot frame, nearest first."""
    out = []
    for a in (0.0, 2.0, 4.0):
        x, y = cx + r * math.cos(a), cy + r * math.sin(a)
        d = math.hypot(x, y)
        out.append(Obstacle(d, x, y, -x / d, -y / d, math.atan2(y, x)))
    return sorted(out, key=lambda o: o.distance_m)


def _homing(keep_m: float, seen_s: float) -> tuple[float, float]:
    """The homing step when the point held 6 cm to the right, last seen at ``seen_s``, and
    the ring's estimate now lies 0.4 m ahead."""
    tracer = Tracer(NOMAD200_LIMITS, TracerParams(home_keep_m=keep_m))
    tracer.s.behaviour = Behaviour.HOME
    tracer.s.home_target = (0.0, -0.06)
    tracer.s.home_seen = seen_s
    v = tracer._home(_walls_round(0.4, 0.0, 1.0), Odometry(0.0, 0.0, 0.0, 0.0, 0.0, 0.0), 10.0, [])
    assert isinstance(v, tuple)
    return v


@pytest.mark.parametrize(
    ("keep_m", "seen_s", "kept"),
    [
        (0.1, 9.5, True),  # 6 cm off, seen half a second ago: the echo changed, not the point
        (0.0, 9.5, False),  # the switch off: homing follows the estimate
        (0.1, 5.0, False),  # not seen for 5 s: the point held is stale
        (0.05, 9.5, False),  # held further off than the switch keeps
    ],
)
def test_homing_keeps_to_its_point_when_the_estimate_jumps(keep_m, seen_s, kept):
    vx, vy = _homing(keep_m, seen_s)
    towards = math.atan2(vy, vx)
    assert abs(towards - (-math.pi / 2 if kept else 0.0)) < math.radians(5), math.degrees(towards)

"""Homing onto a sweep's estimate goes there by dead reckoning while the ring does not hear
the obstacle that put the point there (``TracerParams.home_unheard_m``).

fig13's meet point 9 (seed 3): from 0.44 m off it, the sweep heard a cabinet's corner 0.78 m
away and put the point where it is; the ring, hearing the corner only now and then, found
its three nearest (two walls and a table's corner, 1.33-1.44 m) equidistant where the robot
stood, and the robot settled there again three times and traced on.
"""

from __future__ import annotations

import math

import pytest

from hal.interfaces import NOMAD200_LIMITS
from hal.types import Odometry
from tslam.core.sensing import Obstacle
from tslam.core.tracer import Behaviour, Tracer, TracerParams


def wall(distance: float, bearing_deg: float) -> Obstacle:
    b = math.radians(bearing_deg)
    x, y = distance * math.cos(b), distance * math.sin(b)
    return Obstacle(distance, x, y, -math.cos(b), -math.sin(b), b)


# The ring's three, equidistant about the robot: no cabinet corner among them.
RING = [wall(1.35, 80.0), wall(1.35, 200.0), wall(1.35, -40.0)]


def homing_to_the_sweep(unheard: float) -> Tracer:
    """Sent by the sweep to (0.16, 0.41), its nearest obstacle 0.78 m off at (-0.1, -0.77)."""
    tracer = Tracer(NOMAD200_LIMITS, TracerParams(home_unheard_m=unheard))
    s = tracer.s
    s.behaviour = Behaviour.HOME
    s.home_target = (0.16, 0.41)
    s.home_seen = 0.0
    s.home_swept = (-0.1, -0.77) if unheard > 0.0 else None
    return tracer


@pytest.mark.parametrize("unheard", [0.15, 0.0])
def test_homing_keeps_to_the_sweeps_point_while_the_ring_misses_its_obstacle(unheard):
    tracer = homing_to_the_sweep(unheard)
    odo = Odometry(0.0, 0.0, 0.0, 0.0, 10.0, 10.0)
    out = tracer._home(RING, odo, 1.0, [])
    if unheard:
        assert isinstance(out, tuple) and out[0] * 0.16 + out[1] * 0.41 > 0.0  # on to it
        assert tracer.s.behaviour is Behaviour.HOME
    else:
        assert tracer.s.behaviour is Behaviour.SETTLE  # the ring's point: here


def test_once_the_ring_hears_the_obstacle_the_ring_homes_again():
    tracer = homing_to_the_sweep(0.15)
    odo = Odometry(0.0, 0.0, 0.0, 0.0, 10.0, 10.0)
    heard = [wall(0.78, -97.0), *RING]
    tracer._home(heard, odo, 1.0, [])
    assert tracer.s.home_swept is None


def test_at_the_sweeps_point_the_robot_sweeps_again():
    tracer = homing_to_the_sweep(0.15)
    odo = Odometry(0.16, 0.41, 0.0, 0.0, 10.5, 10.5)
    far = [wall(1.5, b) for b in (80.0, 200.0, -40.0)]  # the corner 1.21 m off, unheard
    tracer._home(far, odo, 1.0, [])
    assert tracer.s.behaviour is Behaviour.SETTLE and tracer.s.sweep is not None

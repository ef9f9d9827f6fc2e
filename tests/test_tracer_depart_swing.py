"""Two tracer rules on obstacles given directly (the ring's sensing stubbed out):

- a departure's pair "straddles the way" only with neither obstacle dead ahead: out of
  office:1's room toward its door, the ring merged the jambs into one obstacle 6 degrees off
  the way, paired it with a side wall on the other side, and the robot traced them into the
  room's corner (``sides_ahead_rad``); and a port the explorer leaves by its own bearing goes
  on straight up to ``until_sides_m`` (``ExplorerParams.own_bearing_until_sides_m``);
- a swing of the trace law's tangent of more than 45 degrees in one cycle is a new pair of
  obstacles, not the edge, and is coasted through for ``swing_coast_s``: in office:1's 5.8 m
  room one side wall fell silent for 2 s and the robot spun round (``swing_coast_s``).
"""

from __future__ import annotations

import math
from dataclasses import replace

from hal.interfaces import NOMAD200_LIMITS
from hal.types import DriveStatus, Odometry
from tslam.core import laws
from tslam.core.sensing import Obstacle
from tslam.core.tracer import Behaviour, Tracer, TracerParams

FREE = DriveStatus(bumper=False, stall=False, motors_on=True, stamp_s=0.0)


def _at(distance: float, bearing_deg: float) -> Obstacle:
    b = math.radians(bearing_deg)
    x, y = distance * math.cos(b), distance * math.sin(b)
    return Obstacle(distance, x, y, -math.cos(b), -math.sin(b), b)


class _Given:
    """A sensor that reports the obstacles it is given."""

    def __init__(self) -> None:
        self.obs: list[Obstacle] = []
        self.points = None

    def update(self, scan, odo) -> list[Obstacle]:
        return self.obs

    def apart(self) -> None:
        return None  # no doorway


def _tracer(params: TracerParams) -> tuple[Tracer, _Given]:
    tracer = Tracer(NOMAD200_LIMITS, params)
    given = _Given()
    tracer.sensor = given
    return tracer, given


def _odo(x: float, t: float) -> Odometry:
    return Odometry(x, 0.0, 0.0, 0.0, t, distance_m=x)


def test_a_pair_with_one_obstacle_dead_ahead_does_not_straddle_the_way():
    # The jambs merged 2.4 m ahead, 6 degrees off the way; a side wall 2.8 m on the right.
    pair = [_at(2.4, 6.0), _at(2.8, -84.0), _at(2.95, 96.0)]
    for ahead_deg, departs_on in ((15.0, True), (0.0, False)):
        tracer, given = _tracer(replace(TracerParams(), sides_ahead_rad=math.radians(ahead_deg)))
        given.obs = pair
        tracer.depart(0.0, _odo(0.0, 0.0))
        tracer.step(None, _odo(0.5, 1.0), FREE, 1.0)
        assert (tracer.behaviour is Behaviour.DEPART) is departs_on, ahead_deg


def test_a_port_left_by_its_own_bearing_goes_on_straight_further():
    # Nothing straddles the way: the jamb ahead and a wall on one side only.
    for until, still_departing in ((3.5, True), (None, False)):
        tracer, given = _tracer(TracerParams())
        given.obs = [_at(2.0, 5.0), _at(2.8, -84.0)]
        tracer.depart(0.0, _odo(0.0, 0.0), until_sides_m=until)
        tracer.step(None, _odo(2.0, 10.0), FREE, 10.0)  # past depart_until_sides_m, 1.5 m
        assert (tracer.behaviour is Behaviour.DEPART) is still_departing, until


def _swing_run(params: TracerParams, wide: float = 2.9, behind: float = 0.5) -> list:
    """Trace a room ``2 * wide`` across for a second, then lose the left wall: the right
    wall and a wall ``behind`` further pair up for 2 s, then the left wall is back. The
    commands of the lost stretch."""
    tracer, given = _tracer(params)
    tracer.s.behaviour = Behaviour.TRACE
    tracer.s.tangent = (1.0, 0.0)
    corridor = [_at(wide, 90.0), _at(wide, -90.0)]
    swung = [_at(wide, -90.0), _at(wide + behind, -150.0)]
    out = []
    for k in range(40):
        t = 0.1 * k
        given.obs = swung if 1.0 <= t < 3.0 else corridor
        twist, _ = tracer.step(None, _odo(0.0, t), FREE, t)
        if 1.0 <= t < 3.0:
            out.append((t, twist))
    return out


def test_a_swing_of_the_tangent_is_coasted_through_in_a_wide_room():
    corridor, swung = (1.0, 0.0), laws.edge_tangent(_at(2.9, -90.0), _at(3.4, -150.0), (1.0, 0.0))
    assert swung is not None and swung[0] < math.cos(math.radians(45.0))  # a swing indeed
    coasting = _swing_run(TracerParams(swing_coast_s=1.5))
    before = coasting[0][1]
    assert before.v_mps > 0.0 and abs(before.steer_radps) < 1e-6  # straight on
    held = [tw for t, tw in coasting if t <= 2.5 + 1e-9]
    assert all(tw == before for tw in held)
    # After swing_coast_s the new pair is taken: the robot turns.
    assert any(abs(tw.steer_radps) > 0.05 for t, tw in coasting if t > 2.6)
    # Without coasting it turns at once; so it does between walls 1 m off, which fall silent
    # for a cycle or two, not seconds (``swing_clearance_m``), unless the new pair's second
    # obstacle lies further than the robot could have moved from the last (``swing_jump_m``).
    no_jump = TracerParams(swing_jump_m=0.0)
    for turning in (_swing_run(TracerParams(swing_coast_s=0.0)), _swing_run(no_jump, 1.0)):
        assert turning[0][1] != before and abs(turning[0][1].steer_radps) > 0.05
    assert corridor != swung


def test_with_jump_a_swing_onto_a_wall_behind_a_lost_echo_is_coasted_at_any_clearance():
    """fig12 seed 4, restarted (noise seed 104, switch ``vertex``): 0.3 m out of the junction
    at (1.44, 1.44) toward its dead-end corner, the ring read the two walls 1.2 m off as one
    obstacle for a cycle, paired it with the block's corner 1.70 m off, and the tangent swung
    round in two steps; the robot went back through the junction and the corner's departure
    was given up."""
    jump = TracerParams(swing_jump_m=0.15)  # the switch ``jump``
    coasting = _swing_run(jump, 1.0)
    before = coasting[0][1]
    assert before.v_mps > 0.0 and abs(before.steer_radps) < 1e-6  # straight on
    assert all(tw == before for t, tw in coasting if t <= 2.5 + 1e-9)
    assert any(abs(tw.steer_radps) > 0.05 for t, tw in coasting if t > 2.6)
    # A new pair as near as the last (a junction's next edge) is taken at once.
    turning = _swing_run(jump, 1.0, behind=0.1)
    assert abs(turning[0][1].steer_radps) > 0.05

"""The tracer's behaviour and what it remembers from one control cycle to the next."""

from __future__ import annotations

import enum
import math
from collections import deque
from dataclasses import dataclass, field

from hal.types import Twist
from tslam.core.edgelength import EdgeOdometer
from tslam.core.sensing import Obstacle
from tslam.core.sweep import Sweep


class Behaviour(enum.Enum):
    ACCESS = "access"
    TRACE = "trace"
    HOME = "home"
    SETTLE = "settle"
    DEPART = "depart"
    BACKOFF = "backoff"


@dataclass
class TracerState:
    behaviour: Behaviour = Behaviour.ACCESS
    tangent: tuple[float, float] | None = None  # odometry frame, unit
    armed: bool = False
    boundary_armed: bool = True
    since: float = 0.0
    settle_tries: int = 0
    sweep: Sweep | None = None
    swept_again: bool = False  # the sweep was doubtful and the turret has turned once more
    home_target: tuple[float, float] | None = None  # homing's last estimate, odometry frame
    # The sweep's nearest obstacle (odometry frame) when homing goes to the sweep's estimate.
    home_swept: tuple[float, float] | None = None
    home_seen: float = 0.0  # when the ring last gave that estimate
    depart_dir: float = 0.0
    depart_from: tuple[float, float] = (0.0, 0.0)
    escape: tuple[float, float] | None = None  # backing off pressed: away from it (odometry)
    depart_m: float = 0.0
    # Control cycles the departure's two obstacles have straddled it, once they did not at
    # first (-1: not looked yet).
    sides_seen: int = -1
    node_distance: float | None = None  # encoder distance at the last node
    node_kind: str = ""
    last_meet: tuple[float, float] | None = None  # odometry frame
    # The last sweep found no meet point there, on a ring that fires fast. Where three
    # obstacles stay nearly equidistant along the edge (a bent wall's two faces and the far
    # side, as at fig12's cut corner), such a ring proposes one close by afresh every cycle,
    # and the robot would sweep there for minutes: the next try must be clear of it.
    rejected: bool = False
    # On any ring: where a sweep last rejected a point (odometry frame). Homing does not
    # hold on through a lost echo (``home_hold_m``) near it: it came back to fig12's cut
    # corner every few seconds for minutes, each time to be rejected again.
    rejected_at: tuple[float, float] | None = None
    left_meet: tuple[float, float] | None = None  # the meet point reported last, left by an edge
    # Where homing began and the edge's tangent there: near a junction the two closest
    # obstacles may belong to another of its edges, so the tangent the trace law keeps while
    # homing wanders can point along the wrong edge. The arrival edge is the one traced in.
    approach: tuple[float, float, float, float] | None = None  # x, y, tangent
    # Where the robot was while tracing (encoder distance, x, y; odometry frame), a metre's
    # worth: the way it really came in. Close to a junction the trace law's tangent can swing
    # onto another of its edges a moment before homing starts.
    trail: deque[tuple[float, float, float]] = field(default_factory=lambda: deque(maxlen=64))
    last_seen: float = 0.0
    until_sides_m: float = 0.0  # this departure's depart_until_sides_m
    sides_pair_m: float = 0.0  # ... and how much nearer one of its two sides may be (0: any)
    swung_at: float | None = None  # when the trace law's tangent swung off the course
    pair_clearance: float = 0.0  # the last pair's distance (d1) as the trace law set the tangent
    pair_far: float = 0.0  # ... and its second obstacle's (d2), and the odometer then
    pair_at_m: float = 0.0
    traced_at: float = -math.inf  # the last cycle the trace law set the tangent
    last_paired: float = -math.inf  # when the trace last had its two obstacles within off_edge_m
    # The edge's length: its own, not the weaving path's, and homing's wander left out (a
    # noisy third echo pulls the circumcentre about): see edgelength.py.
    odometer: EdgeOdometer = field(default_factory=EdgeOdometer)
    last_twist: Twist = field(default_factory=Twist)
    # Which way the base last translated: a contact that stops the robot zeroes the command,
    # and the way out is away from where it was going, not always backwards.
    last_v_sign: float = 1.0
    contacts: list[tuple[float, float, float]] = field(default_factory=list)  # x, y, until
    bumps: list[tuple[float, float, float]] = field(default_factory=list)  # x, y, when
    # A room's door junction reached by access (``room_entry_m``), or the length of an edge
    # to a junction the ring does not show (``stop_at``) traced: the two obstacles there and
    # the bearing back to the door, to report next cycle.
    entry: tuple[list[Obstacle], float | None] | None = None
    # The encoder distance when the trace last went on between two obstacles both behind the
    # robot (a door's jambs it has just passed) on this edge, None if it did not.
    behind_m: float | None = None
    # Homing onto a meet point the ring shows only with a doorway's jambs kept apart; and
    # where the sweep last found none so (odometry frame).
    home_apart: bool = False
    apart_rejected: tuple[float, float] | None = None
    # ``Tracer.arrive_after``: the edge's length and the departures' angles from its end.
    stop_at: tuple[float, tuple[float, ...]] | None = None

"""Access the GVG, trace its edges, home onto meet points, turn back at boundary points.

A hybrid controller (the paper's term) over the laws of ``tslam.core.laws``. It is pure:
each ``step`` takes the latest scan, odometry, drive status and the time, and returns a
drive command and the events the map needs. Which edge to take next at a meet point is
asked of a ``choose`` callback, so the exploration arbiter can decide later; the default
takes the first edge counter-clockwise from the one the robot arrived by. Its parameters,
events and state are in ``tracer_params``, ``tracer_events`` and ``tracer_state``; its
rules at doors in ``doors``.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from hal.interfaces import DriveLimits
from hal.types import DriveStatus, Odometry, SonarScan, Twist
from tslam.core import doors, laws
from tslam.core.frames import TAU, angdiff, offset, to_odom, to_robot
from tslam.core.place import place_obstacles
from tslam.core.sensing import Obstacle, RingSensor
from tslam.core.sweep import BENT_WALL_MERGE_RAD, WIDE_BEND_MERGE_RAD, Sweep, at_minimum_range
from tslam.core.tracer_events import (
    BoundaryReached,
    Chooser,
    EdgeTraversed,
    Event,
    MeetPointReached,
    counter_clockwise_next,
)
from tslam.core.tracer_params import TracerParams
from tslam.core.tracer_state import Behaviour, TracerState

# Re-exported: the map, the arbiter and the programs take them from here.
__all__ = [
    "Behaviour",
    "BoundaryReached",
    "Chooser",
    "EdgeTraversed",
    "Event",
    "MeetPointReached",
    "Tracer",
    "TracerParams",
    "counter_clockwise_next",
]


class Tracer:
    """Runs the laws; ``step`` once per control cycle."""

    def __init__(
        self,
        limits: DriveLimits,
        params: TracerParams | None = None,
        choose: Chooser = counter_clockwise_next,
    ) -> None:
        self.limits = limits
        self.p = params or TracerParams()
        self.choose = choose
        self.sensor = RingSensor(self.p.sensing)
        self.s = TracerState()
        self.s.odometer.detour_ratio = self.p.edge_spike_ratio
        self.s.odometer.back_m = self.p.edge_back_m
        self.obstacles: list[Obstacle] = []
        self._scan: SonarScan | None = None

    @property
    def behaviour(self) -> Behaviour:
        return self.s.behaviour

    def step(
        self, scan: SonarScan, odo: Odometry, status: DriveStatus, now_s: float
    ) -> tuple[Twist, list[Event]]:
        obs = self._with_contacts(self.sensor.update(scan, odo), odo, now_s)
        self.obstacles = obs
        self._scan = scan
        events: list[Event] = []
        if (status.bumper or status.stall) and self.s.behaviour is not Behaviour.BACKOFF:
            hold = self._contact_hold(odo, now_s)
            if hold > 0.0:
                self.s.contacts.append((*self._contact_point(scan, odo), now_s + hold))
            # Touching something means the laws were fed a lie: what the robot touches is
            # inside the sonar's minimum range, invisible to the ring. Back away the way it
            # came (the base drove into it), then re-access.
            if self.s.behaviour is Behaviour.TRACE:
                # The edge ran into something the ring does not hear, so close that it
                # never read as leaving the corner (the boundary rule re-arms only beyond
                # boundary_clearance_m + 0.1): backed off, the robot would trace into it
                # again. fig16 seed 7 touched the indent's back wall eleven times so.
                self.s.boundary_armed = True
            self._back_off(odo, now_s)
        elif status.stall and self.s.behaviour is Behaviour.BACKOFF:
            # Backing off straight pressed into something too: in a corner, against one wall
            # with the wheels turned a degree into it, the base moves neither way, and
            # reversing each time it stalled wedged fig12's robot there for hours.
            away = _away_from_touch(scan)
            if away is not None:
                self.s.escape = to_odom(away, odo)
        v = self._law(obs, odo, now_s, events)
        if v is None:
            twist = Twist(0.0, 0.0, 0.0)
        elif isinstance(v, Twist):
            twist = v
        else:
            twist = laws.to_twist(v, self.limits)
        self.s.last_twist = twist
        if twist.v_mps != 0.0:
            self.s.last_v_sign = math.copysign(1.0, twist.v_mps)
        return twist, events

    def _back_off(self, odo: Odometry, now: float, scan: SonarScan | None = None) -> None:
        """Reverse from where the base was going (``backoff_m``), then re-access; with
        ``scan``, move away from the transducers that read their minimum range instead."""
        s = self.s
        s.behaviour = Behaviour.BACKOFF
        s.entry = None
        s.since = now
        s.depart_from = (odo.x_m, odo.y_m)
        s.depart_dir = -s.last_v_sign
        away = _away_from_touch(scan) if scan is not None else None
        s.escape = to_odom(away, odo) if away is not None else None

    def _contact_point(self, scan: SonarScan, odo: Odometry) -> tuple[float, float]:
        """Where the base touched something (odometry frame): the echo of a transducer at its
        minimum range, the one nearest the way the base was driving; else ``contact_ahead_m``
        along that way (the bumper says that, not where)."""
        way = 0.0 if self.s.last_v_sign > 0 else math.pi
        near = np.flatnonzero(at_minimum_range(scan))
        if len(near):
            i = min(near, key=lambda k: abs(angdiff(float(scan.yaw_rad[k]), way)))
            r = float(scan.ranges_m[i])
            px = float(scan.x_m[i]) + r * math.cos(float(scan.yaw_rad[i]))
            py = float(scan.y_m[i]) + r * math.sin(float(scan.yaw_rad[i]))
        else:
            px, py = self.p.contact_ahead_m * math.cos(way), 0.0
        return offset(to_odom((px, py), odo), odo)

    def _contact_hold(self, odo: Odometry, now: float) -> float:
        """How long to keep the contact just made: ``contact_hold_s``, or ``repeat_hold_s``
        if it is the ``repeat_contacts``-th within ``repeat_contact_m`` of here lately."""
        s, p = self.s, self.p
        s.bumps = [b for b in s.bumps if now - b[2] <= p.repeat_window_s]
        s.bumps.append((odo.x_m, odo.y_m, now))
        here = [
            b for b in s.bumps if math.hypot(b[0] - odo.x_m, b[1] - odo.y_m) <= p.repeat_contact_m
        ]
        if p.repeat_contacts > 0 and len(here) >= p.repeat_contacts:
            return max(p.contact_hold_s, p.repeat_hold_s)
        return p.contact_hold_s

    def _with_contacts(self, obs: list[Obstacle], odo: Odometry, now: float) -> list[Obstacle]:
        """``obs`` and the contacts still kept, nearest first."""
        s = self.s
        s.contacts = [c for c in s.contacts if now <= c[2]]
        if not s.contacts:
            return obs
        out = list(obs)
        for x, y, _ in s.contacts:
            px, py = to_robot((x - odo.x_m, y - odo.y_m), odo)
            d = math.hypot(px, py)
            if d > 1e-6:
                out.append(Obstacle(d, px, py, -px / d, -py / d, math.atan2(py, px)))
        return sorted(out, key=lambda o: o.distance_m)

    # ------------------------------------------------------------------ behaviours
    def _law(
        self, obs: list[Obstacle], odo: Odometry, now: float, events: list[Event]
    ) -> tuple[float, float] | Twist | None:
        s, p = self.s, self.p
        if len(obs) >= 2:
            s.last_seen = now
        b = s.behaviour
        if b is Behaviour.ACCESS:
            if not obs:
                return None
            if laws.equidistant(obs, 2, p.on_edge_tol_m):
                # Keep going the way the robot was tracing, if it was; else along the heading.
                prev = to_robot(s.tangent, odo) if s.tangent else (1.0, 0.0)
                t = laws.edge_tangent(obs[0], obs[1], prev)
                if t is not None:
                    back = doors.room_entry(p, s, obs, odo)
                    if back is not None:
                        # Reported next cycle, stopped here: the arbiter first sees the
                        # robot back on the graph (its excursion straight on, the same edge).
                        s.entry = (obs[:2], back)
                        s.behaviour = Behaviour.TRACE
                        return Twist(0.0, 0.0, 0.0)
                    course, s.tangent = s.tangent, to_odom(t, odo)
                    s.behaviour = Behaviour.TRACE
                    # Re-accessed straight on beside a meet point other than the last (off
                    # the graph where a room's door went out of hearing, office:1's 94 lay
                    # 0.75 m on), the three stand equidistant already: armed, or it is
                    # passed unhomed. Not after turning back: fig12's robot, over m0 and
                    # back, homed onto it naming the edge it had overshot along.
                    s.armed = not laws.equidistant(obs, 3, p.arm_tol_m) or (
                        p.arm_on_access
                        and self._accessed_straight_on(odo, course)
                        and self._new_meet_ahead(obs, odo, anywhere=True)
                    )
                    return self._law(obs, odo, now, events)
            entering = doors.entering(p, s, obs, odo)
            if entering is not None:
                # On along the door's edge, not away from the ring's bearing of the merged
                # jambs, which swings a transducer's spacing: the junction stood at is then
                # on the door's line, and the way back out leads through the door.
                v = (p.access_mps * entering[0], p.access_mps * entering[1])
                return laws.to_twist(v, self.limits, reverse_ok=True)
            v = laws.access_velocity(obs, p.access_mps)
            # Backing away is as good as driving away, and spares a half turn.
            return laws.to_twist(v, self.limits, reverse_ok=True)
        if b is Behaviour.DEPART:
            return self._depart(obs, odo, now)
        if b is Behaviour.BACKOFF:
            gone = math.hypot(odo.x_m - s.depart_from[0], odo.y_m - s.depart_from[1])
            # Bounded in time too: backing into something else must not hold the robot here.
            if gone >= p.backoff_m or now - s.since > 4.0 * p.backoff_m / p.backoff_mps:
                s.behaviour = Behaviour.ACCESS
                return None
            if s.escape is not None:
                ex, ey = to_robot(s.escape, odo)
                v = (p.backoff_mps * ex, p.backoff_mps * ey)
                return laws.to_twist(v, self.limits, reverse_ok=True)
            return Twist(p.backoff_mps * s.depart_dir, 0.0, 0.0)
        if b is Behaviour.TRACE and s.entry is not None:
            (seen, back), s.entry = s.entry, None
            rel, s.stop_at = (s.stop_at[1] if s.stop_at else doors.ACROSS), None
            self._meet(seen, odo, now, events, way_in=back, rel=rel)
            return None
        if s.stop_at is not None and b in (Behaviour.TRACE, Behaviour.HOME) and len(obs) >= 2:
            length = s.odometer.length_to(odo.x_m, odo.y_m)
            if length is not None and length >= s.stop_at[0]:
                s.entry = (obs[:2], None)
                s.behaviour = Behaviour.TRACE
                return Twist(0.0, 0.0, 0.0)
        if b is Behaviour.TRACE:
            return self._trace(obs, odo, now, events)
        if b in (Behaviour.HOME, Behaviour.SETTLE):
            if s.home_apart:
                apart = self.sensor.apart()
                if apart is not None:
                    obs = self._with_contacts(apart, odo, now)
            return self._home(obs, odo, now, events)
        return None

    def _trace(
        self, obs: list[Obstacle], odo: Odometry, now: float, events: list[Event]
    ) -> tuple[float, float] | Twist | None:
        s, p = self.s, self.p
        if len(obs) < 2:
            if now - s.last_seen > p.lost_timeout_s:
                s.behaviour = Behaviour.ACCESS
                return None
            return s.last_twist  # coast briefly through a silent patch
        if not s.armed:
            s.armed = not laws.equidistant(obs, 3, p.arm_tol_m) or self._new_meet_ahead(obs, odo)
        if obs[0].distance_m > p.boundary_clearance_m + 0.1:
            s.boundary_armed = True
        close = obs[0].distance_m < p.boundary_clearance_m
        touching = close and self._touching_ahead(odo)
        if (
            s.boundary_armed
            and close
            and (obs[0].distance_m < p.pinch_clearance_m or self._corner_ahead(odo) or touching)
        ):
            s.boundary_armed = False  # until the robot is clear of this corner again
            self._boundary(obs[0].distance_m, odo, now, events)
            return None
        if touching:
            # Back into the corner just turned back from (the trace law's way flips where
            # the two walls are nearly symmetric), with the boundary rule not re-armed: back
            # off as from a touch, before touching (fig1 seed 35).
            s.boundary_armed = True
            # Away from what it nearly touches, not in reverse: the robot may face out of
            # the corner while the tangent points in.
            self._back_off(odo, now, self._scan)
            return None
        if obs[1].distance_m - obs[0].distance_m > p.off_edge_m and p.doorway_pairs:
            obs = self._doorway(obs, odo, now)
        if obs[1].distance_m - obs[0].distance_m > p.off_edge_m:
            if now - s.last_paired <= p.off_edge_coast_s:
                return s.last_twist
            s.behaviour = Behaviour.ACCESS  # these two are not the edge's obstacles
            return None
        s.last_paired = now
        near = s.armed and self._meet_near(obs, odo)
        apart = self._apart_meet(odo, now) if s.armed and not near else None
        if apart is not None:
            obs = apart
        if near or apart is not None:
            s.home_apart = apart is not None
            s.behaviour = Behaviour.HOME
            s.home_target = None
            if s.tangent is not None and self._approach(odo) is None:
                s.approach = (odo.x_m, odo.y_m, *self._came_along(odo, s.tangent))
            return self._home(obs, odo, now, events)
        # Which way along the edge: the way the robot has come over its last half metre,
        # not the last cycle's tangent alone. One cycle with a false echo nearest (a
        # diffracted corner, a side lobe) pairs the wrong two obstacles, and a tangent that
        # swung round with them once stayed round: the robot went back the way it came.
        along = self._past_rejected or p.course_sign
        course = self._came_along(odo, s.tangent) if s.tangent and along else s.tangent
        prev = to_robot(course, odo) if course else None
        o1, o2 = self._pair(obs, odo, prev)
        out = laws.trace_velocity(o1, o2, prev, p.alpha_mps, p.beta_per_s)
        if out is None:
            return s.last_twist
        v, t = out
        tracing = now - s.traced_at <= 0.5  # the last tangent is this edge's, not a start's
        s.traced_at = now
        if p.swing_coast_s > 0.0 and prev is not None and tracing:
            swung = t[0] * prev[0] + t[1] * prev[1] < math.cos(p.swing_rad)
            # The pair's second obstacle further than the robot could have moved from the
            # last one: that one's echo was lost, and a wall behind it makes the pair.
            jumped = p.swing_jump_m > 0.0 and (
                o2.distance_m - s.pair_far > p.swing_jump_m + abs(odo.distance_m - s.pair_at_m)
            )
            wide = s.pair_clearance >= p.swing_clearance_m
            if swung and (s.swung_at is not None or wide or jumped):
                if s.swung_at is None:
                    s.swung_at = now
                if now - s.swung_at <= p.swing_coast_s:
                    return s.last_twist
            else:
                s.swung_at = None
        s.pair_clearance = o1.distance_m
        behind = all(
            math.cos(o.bearing_rad) * t[0] + math.sin(o.bearing_rad) * t[1]
            < math.cos(p.room_entry_behind_rad)
            for o in (o1, o2)
        )
        if behind:
            s.behind_m = odo.distance_m
        s.pair_far, s.pair_at_m = o2.distance_m, odo.distance_m
        s.tangent = to_odom(t, odo)
        step = laws.step_onto_edge(o1, o2)
        if step is not None:
            s.odometer.on_edge(odo.x_m, odo.y_m, odo.distance_m, to_odom(step, odo))
        if not s.trail or odo.distance_m - s.trail[-1][0] >= 0.02:
            s.trail.append((odo.distance_m, odo.x_m, odo.y_m))
        return v

    def _accessed_straight_on(self, odo: Odometry, course: tuple[float, float] | None) -> bool:
        """Whether the robot, accessing since it last traced along ``course``, went on the
        way it traced."""
        if not self.s.trail or course is None:
            return False
        _, x, y = self.s.trail[-1]
        dx, dy = odo.x_m - x, odo.y_m - y
        gone = math.hypot(dx, dy)
        return gone >= 0.3 and dx * course[0] + dy * course[1] >= gone * math.cos(
            math.radians(30.0)
        )

    def _apart_meet(self, odo: Odometry, now: float) -> list[Obstacle] | None:
        """The obstacles with a doorway's jambs kept two (``RingSensor.apart``) if they make a
        meet point near where the ring's own obstacles do not (``home_apart``); else None. A
        door junction 1.85 m inside a room, by its side wall, heard the merged jambs and the
        wall: two obstacles, and the robot traced on into the room (a floor of six rooms,
        seed 1)."""
        s, p = self.s, self.p
        if not (p.home_apart and p.doorway_pairs and doors.past_door(p, s, odo)):
            return None
        near = s.apart_rejected
        if near is not None and math.dist(near, (odo.x_m, odo.y_m)) < p.rejected_meet_m:
            return None
        apart = self.sensor.apart()
        if apart is None:
            return None
        apart = self._with_contacts(apart, odo, now)
        if not self._meet_near(apart, odo):
            return None
        return apart if doors.jambs_apart(p, apart) else None

    def _doorway(self, obs: list[Obstacle], odo: Odometry, now: float) -> list[Obstacle]:
        """``obs`` with a doorway's jambs two obstacles again, if that puts the robot on an
        edge: the nearest two equidistant where the ring had merged them (``view_ratio``)."""
        apart = self.sensor.apart()
        if apart is None:
            return obs
        apart = self._with_contacts(apart, odo, now)
        if apart[1].distance_m - apart[0].distance_m <= self.p.off_edge_m:
            return apart
        return obs

    def _corner_ahead(self, odo: Odometry) -> bool:
        """Whether the ring hears something close ahead along the edge: the corner it ends
        in, not a doorway it passes through."""
        p, pts = self.p, self.sensor.points
        if self.s.tangent is None or pts is None:
            return True
        tx, ty = to_robot(self.s.tangent, odo)
        ok = ~np.isnan(pts[:, 0])
        x, y = pts[ok, 0], pts[ok, 1]
        r = np.hypot(x, y)
        ahead = (x * tx + y * ty) >= r * math.cos(p.corner_ahead_rad)
        return bool(np.any(ahead & (r < p.corner_ahead_m)))

    def _touching_ahead(self, odo: Odometry) -> bool:
        """Whether a transducer within ``pinch_touch_rad`` of the edge's way reads its minimum
        range: something ahead nearer than the ring can measure."""
        p, scan = self.p, self._scan
        if p.pinch_touch_rad <= 0.0 or scan is None or self.s.tangent is None:
            return False
        tx, ty = to_robot(self.s.tangent, odo)
        near = at_minimum_range(scan)
        ahead = np.cos(scan.yaw_rad) * tx + np.sin(scan.yaw_rad) * ty >= math.cos(p.pinch_touch_rad)
        return bool(np.any(near & ahead))

    def _pair(
        self, obs: list[Obstacle], odo: Odometry, prev: tuple[float, float] | None
    ) -> tuple[Obstacle, Obstacle]:
        """The two obstacles whose edge the robot traces: the two closest, except through a
        spot the sweep has just rejected as a meet point. There three obstacles stay nearly
        equidistant, any two of them are the closest from one cycle to the next, and the
        tangent swings between the edges of every pair: at fig12's cut corner the robot spun
        on the spot for seconds, then went back the way it came. Through such a spot it
        follows the pair whose edge goes on the way it was going."""
        s, p = self.s, self.p
        if (
            not self._past_rejected
            or s.last_meet is None
            or prev is None
            or not laws.equidistant(obs, 3, p.arm_tol_m)
            or math.hypot(odo.x_m - s.last_meet[0], odo.y_m - s.last_meet[1])
            > 2.0 * p.rejected_meet_m
        ):
            return obs[0], obs[1]
        best, pair = -2.0, (obs[0], obs[1])
        for i, j in ((0, 1), (0, 2), (1, 2)):
            t = laws.edge_tangent(obs[i], obs[j], prev)
            along = -2.0 if t is None else t[0] * prev[0] + t[1] * prev[1]
            if along > best:
                best, pair = along, (obs[i], obs[j])
        return pair

    @property
    def _past_rejected(self) -> bool:
        """The last sweep rejected its point on a fast ring, and ``rejected_memory`` is on."""
        return self.s.rejected and self.p.rejected_memory

    def _meet_near(self, obs: list[Obstacle], odo: Odometry) -> bool:
        s, p = self.s, self.p
        if not laws.equidistant(obs, 3, p.meet_tol_m):
            return False
        c = laws.circumcentre(*obs[:3])
        if c is None or math.hypot(*c) > p.meet_radius_m:
            return False
        cx, cy = to_odom(c, odo)
        if self._past_rejected and s.last_meet is not None:
            # Re-arming is not enough on a fast ring: one cycle in which the third echo drops
            # out arms detection again, and the robot homed back onto the point its sweep had
            # just rejected, for minutes (fig12's cut corner through the CAN board).
            off = math.hypot(odo.x_m + cx - s.last_meet[0], odo.y_m + cy - s.last_meet[1])
            if off < p.rejected_meet_m:
                return False
        # Leaving a wide junction, one noisy echo can re-arm detection while the three
        # obstacles are still nearly equidistant: homing then pulls the robot back onto the
        # meet point it has just left, and the departure is lost.
        gone = odo.distance_m - (s.node_distance or 0.0)
        if s.left_meet is None or gone > p.left_meet_travel_m:
            return True  # a loop edge may lead back to it: after this much travel, home
        return math.hypot(odo.x_m + cx - s.left_meet[0], odo.y_m + cy - s.left_meet[1]) > (
            p.left_meet_m
        )

    def _new_meet_ahead(self, obs: list[Obstacle], odo: Odometry, anywhere: bool = False) -> bool:
        """Right after a meet point the three closest obstacles stay nearly equidistant; the
        robot is nearing another meet point only if their circumcentre has moved on, ahead
        (or, ``anywhere``, lies within ``meet_radius_m`` and at least ``left_meet_m`` from
        the last meet point)."""
        s, p = self.s, self.p
        if len(obs) < 3 or (not anywhere and (s.last_meet is None or s.tangent is None)):
            return False
        c = laws.circumcentre(*obs[:3])
        if c is None:
            return False
        cx, cy = to_odom(c, odo)
        far = p.rejected_meet_m if s.rejected else p.new_meet_m
        if anywhere:
            if math.hypot(cx, cy) > p.meet_radius_m:
                return False
            if s.last_meet is None:
                return True
            far = max(far, p.left_meet_m)
        elif s.tangent is None or cx * s.tangent[0] + cy * s.tangent[1] <= 0.0:
            return False  # not ahead
        last = s.last_meet
        if last is None:
            return False
        return math.hypot(odo.x_m + cx - last[0], odo.y_m + cy - last[1]) >= far

    def _home(
        self, obs: list[Obstacle], odo: Odometry, now: float, events: list[Event]
    ) -> tuple[float, float] | Twist | None:
        s, p = self.s, self.p
        if s.behaviour is Behaviour.SETTLE:
            return self._settle(odo, now, events)
        if s.home_swept is not None and s.home_target is not None:
            near = math.hypot(s.home_swept[0] - odo.x_m, s.home_swept[1] - odo.y_m)
            if not obs or obs[0].distance_m > near + p.home_unheard_m:
                held = s.home_target
                return self._home_to(to_robot((held[0] - odo.x_m, held[1] - odo.y_m), odo), now)
        s.home_swept = None
        spread_ok = p.home_spread_m <= 0.0 or laws.equidistant(obs, 3, p.home_spread_m)
        target = laws.circumcentre(*obs[:3]) if len(obs) >= 3 and spread_ok else None
        if target is not None and self._jumped(target, odo, now):
            target = None
        if target is None or math.hypot(*target) > 1.0:
            held = s.home_target
            patient = p.centred_meet and now - s.home_seen < p.home_patience_s
            if held is not None and (patient or self._keeps(held, odo, now)):
                target = to_robot((held[0] - odo.x_m, held[1] - odo.y_m), odo)
            elif (
                held is not None
                and math.hypot(held[0] - odo.x_m, held[1] - odo.y_m) < p.home_hold_m
                and (
                    s.rejected_at is None
                    or math.dist(held, s.rejected_at) >= p.rejected_meet_m
                )
            ):
                # One cycle without the third echo near the point is a dropout, not proof
                # that there is no meet point: go on to where it was, and let the sweep judge
                # it. Giving up here traced on through fig12's m1, never homed onto.
                target = to_robot((held[0] - odo.x_m, held[1] - odo.y_m), odo)
            else:
                # Not a meet point after all (or a bad estimate): back to tracing.
                s.behaviour = Behaviour.TRACE
                s.armed = False
                s.home_target = None
                return None
        else:
            s.home_target = offset(to_odom(target, odo), odo)
            s.home_seen = now
        return self._home_to(target, now)

    def _home_to(self, target: tuple[float, float], now: float) -> tuple[float, float] | Twist:
        """Home towards ``target`` (robot frame); this close, stand and sweep."""
        s, p = self.s, self.p
        if math.hypot(*target) < p.settle_tol_m:
            s.home_swept = None
            s.behaviour = Behaviour.SETTLE
            s.since = now
            s.sweep = Sweep(start_s=now)
            return Twist(0.0, 0.0, p.sweep_radps)
        return laws.homing_velocity(target, p.home_gain, p.home_max_mps)

    def _keeps(self, held: tuple[float, float], odo: Odometry, now: float) -> bool:
        """Whether homing keeps to ``held``: it was this close, and seen a moment ago."""
        p = self.p
        return (
            math.hypot(held[0] - odo.x_m, held[1] - odo.y_m) < p.home_keep_m
            and now - self.s.home_seen < p.lost_timeout_s
        )

    def _jumped(self, target: tuple[float, float], odo: Odometry, now: float) -> bool:
        """Whether the ring's estimate ``target`` (robot frame) left the point homing keeps to."""
        held = self.s.home_target
        if held is None or not self._keeps(held, odo, now):
            return False
        x, y = offset(to_odom(target, odo), odo)
        return math.hypot(x - held[0], y - held[1]) > self.p.home_jump_m

    def _settle(self, odo: Odometry, now: float, events: list[Event]) -> Twist | None:
        """Stand still and sweep the turret, then judge the meet point on the sweep."""
        s, p = self.s, self.p
        assert s.sweep is not None and self._scan is not None
        fixed = p.sweep_fixed_frame
        s.sweep.add(self._scan, self.sensor.history.at(self._scan.stamps_s)[:, 2] if fixed else 0.0)
        if now - s.since < p.sweep_s:
            return Twist(0.0, 0.0, p.sweep_radps)
        centred = p.centred_meet
        doubts: list[float] = []
        obs = s.sweep.obstacles(
            odo.heading_rad if fixed else 0.0,
            WIDE_BEND_MERGE_RAD if centred else BENT_WALL_MERGE_RAD,
            bridge=centred,
            doubts=doubts,
            silent=p.sweep_join_pieces,
            shallow=p.sweep_shallow_bend,
            vertex=p.sweep_vertex,
            recess=p.sweep_recess,
            agree=p.sweep_view_agree,
            silent_view=p.sweep_silent_view,
        )
        if doubts and p.sweep_again and not s.swept_again:
            # One deeper reading between two walls: a stray echo, or a doorway too narrow
            # for the sweep's spacing. Another turn of the turret puts readings between.
            s.swept_again = True
            s.since = now
            return Twist(0.0, 0.0, p.sweep_radps)
        turns = 2.0 if s.swept_again else 1.0
        s.swept_again = False
        s.settle_tries += 1
        fast_ring = s.sweep.firings_per_transducer / turns > p.fast_ring_firings
        touching = s.sweep.touching
        s.sweep = None
        centre = laws.wall_centre if centred else laws.circumcentre
        swept = centre(*obs[:3]) if len(obs) >= 3 else None
        if swept is not None and math.hypot(*swept) > p.converge_tol_m and s.settle_tries < 3:
            s.behaviour = Behaviour.HOME
            # Home on the sweep's estimate: the ring may not resolve the third obstacle
            # at all (a cabinet's corner 45 degrees from a wall, fig13's meet point 0).
            s.home_target = offset(to_odom(swept, odo), odo)
            s.home_seen = now
            # Metres off, the sweep missed one of the point's obstacles, not the ring.
            near = p.home_unheard_m > 0.0 and bool(obs) and math.hypot(*swept) <= p.meet_radius_m
            s.home_swept = offset(to_odom((obs[0].x_m, obs[0].y_m), odo), odo) if near else None
            return None
        s.settle_tries = 0
        converged = swept is not None and math.hypot(*swept) <= p.converge_tol_m
        if converged and (centred or p.spread_at_estimate):
            at = laws.seen_from(obs, swept)
            order = sorted(range(len(obs)), key=lambda i: at[i])
            obs = [replace(obs[i], distance_m=at[i]) for i in order]
        # Something within the ring's minimum range, which the sweep's obstacles leave out
        # (too few firings hear it): the walls the point is equidistant to are not the
        # nearest. fig13 seed 9 homed onto three walls 1.7 m off with a cabinet's corner
        # 0.27 m from its centre, and reported that as a meet point 0.99 m from any.
        if swept is None or touching or not laws.equidistant(obs, 3, p.meet_spread_m):
            # Three obstacles came close to equidistant but never met: the edge goes on.
            s.behaviour = Behaviour.TRACE
            if s.home_apart:
                # Homed for the ring's finer reading only: what the ring reads as ever may
                # still be a meet point here (fig13's close pairs by a cabinet's gap), so
                # this is no rejection; only that reading is not asked here again.
                s.home_apart = False
                s.apart_rejected = (odo.x_m, odo.y_m)
                return None
            s.armed = False
            # With centred_meet, where the rejected point is: the sweep's estimate if it
            # is about here, else here. An estimate metres off (three walls far from
            # equidistant) made any estimate here look new, and the robot homed and swept
            # at fig12's cut corner for minutes.
            near = swept is not None and (not centred or math.hypot(*swept) <= p.meet_radius_m)
            s.last_meet = offset(to_odom(swept, odo), odo) if near else (odo.x_m, odo.y_m)
            s.rejected = fast_ring
            s.rejected_at = (odo.x_m, odo.y_m)
            # On the way it came in: while homing, the trace law's tangent swings between
            # the pairs of nearly equidistant walls, and at fig12's cut corner it had swung
            # round, so the robot went back down the edge it had come up. At fig16's weak
            # meet point (seed 5) that turned the robot back mid-corridor, and the explorer
            # called a third of the corridor the whole map.
            a = self._approach(odo)
            if a is not None:
                s.tangent = (a[2], a[3])
            return None
        point = offset(to_odom(swept, odo), odo) if converged and p.length_at_estimate else None
        self._meet(obs, odo, now, events, point)
        return None

    def _meet(
        self,
        obs: list[Obstacle],
        odo: Odometry,
        now: float,
        events: list[Event],
        point: tuple[float, float] | None = None,
        way_in: float | None = None,
        rel: tuple[float, ...] | None = None,
    ) -> None:
        """Report the meet point the robot stands at and set off along the departure the
        arbiter chooses (``way_in``: the bearing of the way in, known, else from the trail;
        ``rel``: the departures' angles from the way in, as the map has them, not read)."""
        s, p = self.s, self.p
        s.rejected_at = None
        found_by = "entry" if way_in is not None else "homing" if rel is None else "length"
        near = [o for o in obs if o.distance_m - obs[0].distance_m <= p.degree_tol_m]
        around = place_obstacles(obs, near, p.place_radius_m, p.place_tol_m, p.place_corners)
        bearings = laws.departure_bearings(around)
        deps = sorted((odo.heading_rad + b) % TAU for b in bearings)
        arrival = None
        tangent = s.tangent
        a = self._approach(odo)
        if a is not None:
            tangent = (a[2], a[3])
        if tangent is not None:
            back = math.atan2(-tangent[1], -tangent[0]) % TAU
            arrival = min(range(len(deps)), key=lambda k: angdiff(deps[k], back))
        if way_in is None and p.unseen_way_in_rad > 0.0 and rel is None:
            way_in = self._unseen_way_in(odo)
        if way_in is not None and min(angdiff(d, way_in) for d in deps) > p.unseen_way_in_rad:
            deps = sorted((*deps, way_in))
            arrival = deps.index(way_in)
        if rel is not None:
            # Not homed: the way back is the door's line, or the chord to where the edge
            # began (the trace law's tangent swings by a transducer's spacing); the rest
            # are given.
            back = way_in if way_in is not None else doors.way_back(s, odo)
            deps = sorted((back + r) % TAU for r in rel)
            arrival = min(range(len(deps)), key=lambda k: angdiff(deps[k], back))
        base = deps[arrival] if arrival is not None else 0.0
        rel = tuple(sorted((d - base) % TAU for d in deps))
        clearance = sum(o.distance_m for o in near) / len(near)
        length = self._edge_done(odo, now, "meet", events, point)
        ev = MeetPointReached(
            now, odo.x_m, odo.y_m, clearance, len(deps), tuple(deps), arrival, rel, length,
            found_by,
        )  # fmt: skip
        events.append(ev)
        s.last_meet = s.left_meet = (odo.x_m, odo.y_m)
        s.rejected = False
        k = self.choose(ev)
        self._start_depart(deps[k], odo)

    def _boundary(self, clearance: float, odo: Odometry, now: float, events: list[Event]) -> None:
        s = self.s
        length = self._edge_done(odo, now, "boundary", events)
        events.append(BoundaryReached(now, odo.x_m, odo.y_m, clearance, length))
        assert s.tangent is not None
        s.left_meet = None  # the way back leads to it: homing onto it is wanted now
        back = math.atan2(-s.tangent[1], -s.tangent[0])
        self._start_depart(back, odo, distance=0.0)

    def _edge_done(
        self,
        odo: Odometry,
        now: float,
        kind: str,
        events: list[Event],
        point: tuple[float, float] | None = None,
    ) -> float | None:
        s = self.s
        x, y = point if point is not None else (odo.x_m, odo.y_m)
        length = s.odometer.length_to(x, y)  # None before the first node
        if length is not None:
            events.append(EdgeTraversed(now, length, s.node_kind, kind))
        s.odometer.start(x, y)
        s.node_distance = odo.distance_m
        s.node_kind = kind
        return length

    def _came_along(self, odo: Odometry, tangent: tuple[float, float]) -> tuple[float, float]:
        """The direction the robot came in along: from where it traced ``approach_look_m``
        of travel ago (dead reckoning is good over that), on a shorter edge from where it
        departed (``approach_short_m``), else the trace law's tangent."""
        s, p = self.s, self.p
        back = [q for q in s.trail if q[0] <= odo.distance_m - p.approach_look_m]
        if not back and s.trail and p.approach_short_m > 0.0:
            # A short edge: the way since the departure is all there is behind. The trace
            # law's tangent is no guide here: between a close pair's nearly equidistant
            # walls it swings round (fig13 seed 3: 0.35 m west from one point of its 0.53 m
            # pair to the other with the tangent pointing east, and the edge was mapped on
            # the departure opposite the one it came in by).
            dx, dy = odo.x_m - s.depart_from[0], odo.y_m - s.depart_from[1]
            n = math.hypot(dx, dy)
            if n >= p.approach_short_m and odo.distance_m - s.trail[0][0] < p.approach_look_m:
                return dx / n, dy / n
        if not back or odo.distance_m - back[-1][0] > 2.0 * p.approach_look_m:
            return tangent  # a detour or a fresh start since: no straight stretch behind
        _, x, y = back[-1]
        dx, dy = odo.x_m - x, odo.y_m - y
        n = math.hypot(dx, dy)
        if n < 0.5 * p.approach_look_m:
            return tangent
        return dx / n, dy / n

    def _unseen_way_in(self, odo: Odometry) -> float | None:
        """The bearing (odometry frame) from here back along the traced way in to a point
        ``way_in_m`` off, if the robot traced it lately and about straight; None if not."""
        p = self.p
        for d, x, y in reversed(self.s.trail):
            travelled = odo.distance_m - d
            if travelled > 2.5 * p.way_in_m:
                return None
            chord = math.hypot(x - odo.x_m, y - odo.y_m)
            if chord >= p.way_in_m:
                if travelled > p.way_in_bent * chord:
                    return None
                return math.atan2(y - odo.y_m, x - odo.x_m) % TAU
        return None

    def arrive_after(self, length_m: float, rel_rad: tuple[float, ...]) -> None:
        """On the edge just departed along, stand at the junction at its end once
        ``length_m`` of it is traced, and report it with departures at ``rel_rad`` from the
        way in: a junction the ring does not show from this side (a room's door junction
        seen along the room's edge, ``room_entry_m``)."""
        self.s.stop_at = (length_m, tuple(rel_rad))

    def _approach(self, odo: Odometry) -> tuple[float, float, float, float] | None:
        """Where homing onto this meet point began, if it began close enough to count."""
        a = self.s.approach
        if a is None or math.hypot(odo.x_m - a[0], odo.y_m - a[1]) > self.p.approach_keep_m:
            return None
        return a

    def depart(
        self,
        direction_rad: float,
        odo: Odometry,
        until_sides_m: float | None = None,
        sides_pair_m: float = 0.0,
    ) -> None:
        """Leave the meet point the robot stands at along ``direction_rad`` (odometry frame):
        for an arbiter that held the robot there and has since decided where to go. Going on
        straight until the edge's two obstacles straddle the way, up to ``until_sides_m``
        (None: ``depart_until_sides_m``), and with ``sides_pair_m`` the two no further apart
        than that in distance: the sweep did not show this departure, and the two nearest may
        be no edge's pair yet."""
        self._start_depart(direction_rad, odo)
        if until_sides_m is not None:
            self.s.until_sides_m = until_sides_m
        self.s.sides_pair_m = sides_pair_m

    def go_straight(self, distance_m: float) -> None:
        """On a departure just begun, go on straight along it at least ``distance_m`` from the
        meet point before tracing."""
        if self.s.behaviour is Behaviour.DEPART:
            self.s.depart_m = max(self.s.depart_m, distance_m)

    def _start_depart(self, direction: float, odo: Odometry, distance: float | None = None) -> None:
        s = self.s
        s.behaviour = Behaviour.DEPART
        s.depart_dir = direction
        s.depart_from = (odo.x_m, odo.y_m)
        s.trail.clear()  # a new edge: the way in is measured along it alone
        s.tangent = (math.cos(direction), math.sin(direction))
        s.armed = False
        s.depart_m = self.p.depart_m if distance is None else distance
        s.sides_seen = -1
        s.until_sides_m = self.p.depart_until_sides_m
        s.sides_pair_m = 0.0
        s.approach = None
        s.stop_at = None
        s.home_apart = False
        s.apart_rejected = None
        s.behind_m = None

    def _depart(
        self, obs: list[Obstacle], odo: Odometry, now: float
    ) -> tuple[float, float] | Twist | None:
        s, p = self.s, self.p
        err = (s.depart_dir - odo.heading_rad + math.pi) % TAU - math.pi
        gone = math.hypot(odo.x_m - s.depart_from[0], odo.y_m - s.depart_from[1])
        if s.sides_pair_m > 0.0 and p.door_steer_m > 0.0:
            # Out toward a door the ring merged from afar (``door_steer_m``): its jambs are
            # two as soon as the view between them shows (``RingSensor.apart``).
            apart = self.sensor.apart()
            gap = None if apart is None else doors.door_ahead(p, s, apart, err)
            if gap is not None:
                s.depart_dir = (odo.heading_rad + gap[0]) % TAU
                err = gap[0]
                if gap[1] > p.door_steer_m:
                    return (p.alpha_mps * math.cos(err), p.alpha_mps * math.sin(err))
        if gone >= s.depart_m and abs(err) < math.radians(15) and self._sides_seen(obs, err, gone):
            s.behaviour = Behaviour.TRACE
            return None
        if abs(err) > math.radians(10) and gone < 0.02:
            return Twist(0.0, laws.steer_rate(err, self.limits), 0.0)
        return (p.alpha_mps * math.cos(err), p.alpha_mps * math.sin(err))

    def _sides_seen(self, obs: list[Obstacle], err: float, gone: float) -> bool:
        """Whether tracing may begin this far out along a departure ``err`` off the heading.

        A departure leaves between two obstacles, so the edge's pair lies one on each side of
        it. From a junction by a doorway the ring's transducers, 22.5 degrees apart, do not
        see between the jambs: it merges them into one obstacle, and the two closest it
        reports, a jamb and the wall beside it, lie on one side; tracing them leads along the
        wall, not through the door. Going on straight until the pair straddles the way (the
        jambs a few decimetres off are far apart in bearing) takes the robot into the door."""
        p = self.p
        if gone >= self.s.until_sides_m or len(obs) < 2:
            return True
        if obs[0].distance_m < p.boundary_clearance_m + 0.1:
            return True  # something close ahead: the trace law and its boundary rule decide
        a, b = ((o.bearing_rad - err + math.pi) % TAU - math.pi for o in obs[:2])
        way = (math.cos(err), math.sin(err))
        t = laws.edge_tangent(obs[0], obs[1], way)
        # Their edge must also run along the way: a wall behind on the other side (the
        # table beside fig14's door) makes a pair that straddles it, of another edge.
        within = p.sides_along_rad
        if self.s.sides_pair_m > 0.0 and p.own_sides_along_rad > 0.0:
            within = min(within, p.own_sides_along_rad)
        along = t is not None and t[0] * way[0] + t[1] * way[1] >= math.cos(within)
        # The ring glimpses the far jamb now and then before it holds it: a glimpse
        # traced from is the jamb-and-wall edge again a cycle later.
        # And neither lies dead ahead: that is what the robot is driving at, not a side. Out
        # of office:1's room toward its door, 2.4 m off, the ring merged the jambs into one
        # obstacle 6 degrees off the way, paired it with a side wall, and traced into the
        # room's corner.
        ahead = min(abs(a), abs(b)) < p.sides_ahead_rad
        ok = along and (a > 0.0) != (b > 0.0) and not ahead
        if self.s.sides_pair_m > 0.0:
            # And, on a departure the arbiter asked that of, about as far (``depart``).
            ok = ok and obs[1].distance_m - obs[0].distance_m <= self.s.sides_pair_m
        if self.s.sides_seen < 0 and ok:
            return True  # as almost everywhere: the pair is there at ``depart_m``
        self.s.sides_seen = self.s.sides_seen + 1 if ok else 0
        return self.s.sides_seen >= p.sides_cycles


def _away_from_touch(scan: SonarScan) -> tuple[float, float] | None:
    """The unit vector (robot frame) away from every transducer that reads its minimum
    range (something nearer than it can measure), or None if none does or they cancel."""
    near = at_minimum_range(scan)
    if not near.any():
        return None
    x = -float(np.sum(np.cos(scan.yaw_rad[near])))
    y = -float(np.sum(np.sin(scan.yaw_rad[near])))
    norm = math.hypot(x, y)
    return (x / norm, y / norm) if norm > 1e-6 else None

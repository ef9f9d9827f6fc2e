"""A junction whose mapped way in was read askew: found again at the end of its known edge
with every other departure where the map has it.

A sweep that misses one wall puts a departure at the bisector of the walls either side of
the gap: fig14's junction by the lab's east wall (true meet point 14, drift paper, seed 3)
was first read with its south edge at 211 degrees, not 285. The robot went out by it, the
trace law took it south, and the edge was mapped on that port. Back up that edge, the
junction read right: its arrival edge was 74 degrees off the port the map has for it, so
the place was not recognised, and mapped again; a later merge zipping the two readings
together was refused ("looks otherwise"), and their fragment stayed copies.

The edge's length, the clearance and every other departure, under a turn no larger than
dead reckoning's heading drift since the node was read, say where the robot is; the
arrival port's angle is then read again from this arrival, which the robot has just traced
in by. Only at a junction of four edges or more: with three, the two departures left agree
on one angle only, and in a walk of fig13's graph (tests/test_explorer_past.py) a junction
was so recognised at the end of another edge as long, its port turned 67 degrees, and the
map went wrong from there.
"""

from __future__ import annotations

import math

from tslam.core.explorer_state import ExplorerState, angdiff
from tslam.core.frames import TAU
from tslam.core.tracer import MeetPointReached


class Askew(ExplorerState):
    """Recognising a junction whose arrival port the map has at the wrong angle."""

    def _read_askew(
        self,
        ev: MeetPointReached,
        w: int,
        q: int,
        length: float | None,
        mapped: float,
        slack_m: float = 0.0,
    ) -> int | None:
        """The rotation under which ``ev``, arriving at node ``w`` by its port ``q`` after
        an edge of ``mapped`` metres, is ``w`` with that port read askew; None if it is not
        (see the module). Port ``q`` is then read again at the angle it arrived by."""
        a, wn, tol = ev.arrival_index, self.map.node(w), self._tol(slack_m)
        if (
            not self.p.askew_arrival
            or a is None
            or self.partial_m > 0
            or length is None
            or wn.kind != "meet"
            or wn.degree != ev.degree
            or wn.degree < 4
            or w in self.stored
            or not tol.length_ok(length, mapped)
            or abs(ev.clearance_m - wn.clearance_m) > tol.clearance_m
        ):
            return None
        k = (q - a) % ev.degree
        n = ev.degree
        others = [i for i in range(n) if i != a]
        diffs = [wn.departures_rad[(i + k) % n] - ev.departures_rad[i] for i in others]
        turn = math.atan2(sum(map(math.sin, diffs)), sum(map(math.cos, diffs)))
        if angdiff(turn, 0.0) > self._turn_bound(w):
            return None
        if any(angdiff(d, turn) > tol.angle_rad for d in diffs):
            return None
        way_in = (ev.departures_rad[a] + turn) % TAU
        if angdiff(way_in, wn.departures_rad[q]) <= tol.angle_rad:
            return None  # not askew: the signature itself said no
        deps = list(wn.departures_rad)
        deps[q] = way_in
        # The port keeps its place among the others, or the reading is of another place.
        if any(deps[p] >= deps[p + 1] for p in range(n - 1)):
            return None
        was = math.degrees(wn.departures_rad[q])
        self._reread_node(w, tuple(deps), wn.clearance_m, {p: p for p in range(n)})
        self._note(
            f"node {w} recognised by its other {n - 1} departures and edge length; its port "
            f"{q}, mapped at {was:.0f} degrees, read again at {math.degrees(way_in):.0f}"
        )
        return k

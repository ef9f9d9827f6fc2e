"""Which map node the robot has homed onto, and what that arrival says: the node expected at
the end of a known edge, a new node (and the old ones it may be), a node it bounced back to.
"""

from __future__ import annotations

import math

from tslam.core.explorer_state import MAX_CUTS, ExplorerState, Past, angdiff, nearest
from tslam.core.localize import Hypothesis, Prediction, arrival_matches, candidates, predict
from tslam.core.portmap import PortMap, bearing_shift, merged_by_bearing
from tslam.core.signature import Signature
from tslam.core.tracer import MeetPointReached


class Arrival(ExplorerState):
    """Reading a meet-point arrival against the map."""

    def _arrive(self, ev: MeetPointReached) -> tuple[int, PortMap]:
        """Which map node the robot has homed onto, and which of the event's departures is
        which of its ports."""
        self._misread = None
        node, rot = self._identify(ev)
        self._own_readings_back(node)
        if isinstance(rot, PortMap):
            return node, rot
        return node, PortMap.rotation(rot, ev.degree, ev.arrival_index)

    def _identify(self, ev: MeetPointReached) -> tuple[int, int | PortMap]:
        """The node, and the rotation (event index i is port ``(i + rot) % degree``) or, for
        a junction read with another degree, the port map."""
        a = ev.arrival_index
        length = self._edge_length(ev.edge_length_m)
        resuming, self._resuming = self._resuming, False
        short, self._short_from = self._short_from, None
        if self.leaving is None or self.detoured or a is None:
            return self._lost(ev, "off the graph", resuming)
        back = self._back_from_short_end(ev, short)
        if back is not None:
            return back
        f, j = self.leaving
        bounced = self._bounced(ev)
        if bounced is not None:
            return bounced
        if short is not None:
            # Not the edge's far end (the robot turned back short of it), and not where it
            # left: nothing on the edge says where it is.
            self._failed(f, j)
            return self._lost(ev, f"not back where node {f} was left for the dead end")
        e = self.map.node(f).ports[j]
        seen = self._seen(ev, a, f)
        if e is not None:
            return self._expected(ev, seen, f, j, e, length)
        went = self._walked_to(ev, a, length, back=True)
        if went is None:
            went = self._went_otherwise(ev, a, f, j, length, known=False)
        if went is not None:
            return went
        return self._new_edge(ev, seen, f, self._departure_taken(f, j), length)

    def _bounced(self, ev: MeetPointReached) -> tuple[int, PortMap] | None:
        lv, p = self._last_visit, self.p
        if lv is None or self.leaving is None or ev.edge_length_m is None:
            return None
        node, deps, pm, x, y = lv
        length = ev.edge_length_m
        # Further out, a U-turn: back by the departure it left by, which dead reckoning,
        # good over an edge (section V-C), places where it left (fig12 seed 2: 9.3 m out and
        # back along its long edge, and the junction was mapped again).
        far = length > p.bounce_length_m
        # Or at the place's other point: fig13 seed 5 went 0.45 m out of the 0.29 m pair and
        # back, homed 0.35 m from where it had left, read the place's four edges as before,
        # and mapped it again. The bearings below tell a twin junction that far.
        reach = max(p.bounce_m + (p.bounce_rel * length if far else 0.0), p.bounce_place_m)
        if node != self.leaving[0] or not self.map.has_node(node):
            return None
        moved = math.hypot(ev.x_m - x, ev.y_m - y)
        if (
            self.p.place_hop_same
            and ev.degree == len(deps)
            and p.bounce_m < moved
            and max(length, moved) <= p.place_hop_m
        ):
            # The place's other point, read as the place again (fig16's weak meet point
            # 0.36 m into the indent, read with the place's four edges as the corridor's
            # meet point was): one node, its ports matched by absolute bearing.
            return self._spans(node, moved, self._reread(ev, node, deps, pm, moved))
        if ev.degree != len(deps):
            if max(length, moved) > p.place_hop_m:
                return None
            if ev.degree > len(deps) and ev.degree >= self.map.node(node).degree:
                placed = self._read_place(ev, node)
                if placed is not None:
                    return self._spans(node, moved, placed)
            return self._spans(node, moved, self._reread(ev, node, deps, pm, moved))
        if (far and length > p.bounce_far_m) or moved > reach:
            return None

        # Same place, seconds later: absolute bearings still agree, so they fix the rotation.
        # A twin junction a few decimetres away has other bearings (one of its edges leads
        # back to the point just left), which tells it from a bounce.
        shift = bearing_shift(ev.departures_rad, deps, p.bounce_angle_rad)
        if shift is None:
            return None
        key = self.leaving
        pm = pm.shifted_events(shift, ev.degree)
        a = ev.arrival_index
        arrival = next((p for p, i in enumerate(pm.index) if i == a), None)
        if far and arrival != key[1]:
            return None  # round a loop, maybe: dead reckoning alone does not close loops
        self._count_bounce(key)
        self._note(f"back at node {node}: departure {key[1]} could not be held")
        return node, PortMap(pm.index, arrival)

    def _spans(
        self, node: int, moved: float, found: tuple[int, PortMap] | None
    ) -> tuple[int, PortMap] | None:
        """``found`` as it is; if it is ``node``, read again ``moved`` off, the place spans
        that much: an edge to it may end at either of its points (``_expected``)."""
        if found is not None and found[0] == node:
            self._widen_span(node, moved)
        return found

    def _widen_span(self, node: int, apart: float) -> None:
        """``node``'s place was read at two points ``apart`` metres apart (with
        ``place_span_slack``; ``_expected`` allows for it)."""
        if self.p.place_span_slack:
            self.span[node] = max(self.span.get(node, 0.0), apart)

    def _beside(self, node: int) -> bool:
        """Whether ``node`` has a mapped edge to another meet point no shorter than a place
        is wide (``place_hop_m``: fig16's weak meet point, 0.41 m from the corridor's, is
        the same place) and shorter than ``grow_beside_m``."""
        n, lo, hi = self.map.node(node), self.p.place_hop_m, self.p.grow_beside_m
        for port, e in enumerate(n.ports):
            if e is None or not lo <= self.map.edge(e).length_m < hi:
                continue
            far = self.map.edge(e).other_end(node, port)[0]
            if far != node and self.map.node(far).kind == "meet":
                return True
        return False

    def _reread(
        self,
        ev: MeetPointReached,
        node: int,
        deps: tuple[float, ...],
        pm: PortMap,
        moved: float = 0.0,
    ) -> tuple[int, PortMap] | None:
        """The junction just left, read again within ``place_hop_m`` with another number of
        edges: the robot homed again, onto one point of a close pair it had read as their
        place, or onto the place whose point it had read alone (when ``_read_place`` may not
        make the node the place) (fig13 seed 1: its 0.29 m pair read with four edges, then
        6 cm on with three, and mapped twice). The robot stands at the node; its ports are
        matched to the departures by their absolute bearings, which a few seconds do not
        turn. Also read so with the same degree (``place_hop_same``). ``moved``: how far
        from where it was read last; further than ``bounce_m``, the robot is at the place's
        other point, and may go on by the departure it was leaving by."""
        now = ev.departures_rad
        ports = [deps[i] for i in pm.index]
        index = [nearest(b, now) for b in ports]
        tol = self.p.bounce_angle_rad
        agree = sum(angdiff(now[i], b) <= tol for i, b in zip(index, ports, strict=True))
        if agree < min(ev.degree, len(ports)) - 1:
            return None
        key = self.leaving
        assert key is not None
        arrival = next((q for q, i in enumerate(index) if i == ev.arrival_index), None)
        on = self.p.on_through_place and moved > self.p.bounce_m
        if on and index[key[1]] != ev.arrival_index and self._on_by_count.get(key, 0) < 2:
            # The departure leaves from here too, not by the way the robot came in: it homed
            # at the place's other point on the way (fig16's weak meet point, 0.36 m into
            # the indent from the corridor's), and no departure was lost. Twice at most for
            # a departure: a robot sent back and forth between the two points is bouncing.
            self._on_by = key
            self._on_by_count[key] = self._on_by_count.get(key, 0) + 1
            self._note(f"at node {node}'s other point, read with {ev.degree} edges: on by {key[1]}")
            return node, PortMap(tuple(index), arrival)
        self._count_bounce(key)
        self._note(f"back at node {node}, read with {ev.degree} edges: departure {key[1]} not held")
        return node, PortMap(tuple(index), arrival)

    def _read_place(self, ev: MeetPointReached, node: int) -> tuple[int, PortMap] | None:
        """The meet point just left, a few decimetres back, read with more edges from here:
        the two are one place, and the node becomes the place (fig16 seed 3: the corridor's
        meet point read alone with three edges, then the weak one 0.36 m on with the
        place's four, mapped as a new node; the robot came back to the first and mapped it
        again). Its explored ports move to the place's departures by absolute bearing; its
        unexplored ones that match none led inside the place. Not while a hypothesis places
        the node: its rotation would not survive the new ports."""
        n = self.map.node(node)
        now, tol = ev.departures_rad, self.p.bounce_angle_rad
        carry: dict[int, int] = {}
        for p, b in enumerate(n.departures_rad):
            i = nearest(b, now)
            if angdiff(now[i], b) <= tol and i not in carry.values():
                carry[p] = i
        explored = [p for p, e in enumerate(n.ports) if e is not None]
        if len(carry) < n.degree - 1 or any(p not in carry for p in explored):
            return None
        return self._become_place(ev, node, carry, None)

    def _become_place(
        self, ev: MeetPointReached, node: int, carry: dict[int, int], arrival: int | None
    ) -> tuple[int, PortMap] | None:
        """Node ``node`` read again as its place: its ports become ``ev``'s departures, port
        ``p`` moving to departure ``carry[p]``; None while a hypothesis places the node (its
        rotation would not survive the new ports)."""
        if self._in_hypotheses(node):
            return None
        # Between the clearances of the place's two points, whichever this is: the robot
        # comes back to either (fig16 seed 24: the place read at the weak meet point, 0.90 m,
        # took the corridor's 1.14 m for another place, and the corridor was mapped again).
        clearance = 0.5 * (self.map.node(node).clearance_m + ev.clearance_m)
        self._reread_node(node, ev.departures_rad, clearance, carry)
        if self._odo is not None:
            self.born[node] = self._odo.distance_m
        self._note(f"node {node} read again as its place, with {ev.degree} edges")
        return node, PortMap(tuple(range(ev.degree)), arrival)

    def _back_by_bearings(
        self, ev: MeetPointReached, w: int, q: int
    ) -> tuple[PortMap, float] | None:
        """Back from a dead end by port ``q`` of ``w``, the node read last, within ``twin_m``
        of where it was read or within the place it was read at (``place_hop_m`` at most):
        the departures' absolute bearings, still good over the way out and back, say which is
        which, and the one they give port ``q`` is the way the robot came in, whichever the
        tracer took for it. fig16 seed 18, back from the indent's dead end at the place's
        other point 0.41 m from where it was read, took the indent's other departure for its
        way in (the one at 291 degrees, not at 235; the place's reading had it at 252): "lost
        (expected node 1 ...)", and the place and its corridor were mapped again. The port
        map and how far the robot homed from where it read ``w``; None if the bearings do not
        all agree within ``bounce_angle_rad`` under one shift."""
        lv = self._last_visit
        if lv is None or lv[0] != w:
            return None
        _, deps, pm, x, y = lv
        moved = math.hypot(ev.x_m - x, ev.y_m - y)
        # Further than a twin junction lies, only within the place the node was read at.
        reach = min(self.p.place_hop_m, self.p.twin_m + self.span.get(w, 0.0))
        d = self.map.node(w).degree
        if moved > reach or len(pm.index) != d:
            return None
        tol = self.p.bounce_angle_rad
        if ev.degree == len(deps) == d:
            shift = bearing_shift(ev.departures_rad, deps, tol)
            if shift is None:
                return None
            return PortMap(pm.shifted_events(shift, ev.degree).index, q), moved
        if not self.p.back_merged or ev.degree != d - 1 or not len(set(pm.index)) == len(deps) == d:
            return None
        # Read with two of its edges as one, which the last reading had apart (fig16 seed 18,
        # back from the indent at the weak meet point: the corridor's two edges as one
        # departure). Matched by angle to the node's ports, read at its other point, the
        # indent's second edge shared the first's departure; left by a bearing between them,
        # the robot went into the first's dead end three times, and gave the second up.
        merged = merged_by_bearing(ev.departures_rad, deps, tol)
        if merged is None:
            return None
        return PortMap(tuple(merged[i] for i in pm.index), q), moved

    def _by_bearings(
        self, ev: MeetPointReached, f: int, w: int, pm: PortMap, moved: float
    ) -> PortMap:
        """``w`` arrived at as ``_back_by_bearings`` reads it."""
        if ev.degree != len(pm.index):
            shared = [p for p, i in enumerate(pm.index) if pm.index.count(i) > 1]
            self._note(
                f"node {w} read again back from boundary {f} with {ev.degree} edges, by its "
                f"bearings: departures {' and '.join(map(str, shared))} as one"
            )
            self._misread = w
        elif ev.arrival_index != pm.index[pm.arrival]:
            self._note(
                f"node {w} read again back from boundary {f}, by its bearings: in by departure "
                f"{pm.index[pm.arrival]}, not {ev.arrival_index}"
            )
        self._spans(w, moved, (w, pm))
        self.partial_m = 0.0
        return pm

    def _short_of_place(
        self,
        ev: MeetPointReached,
        seen: Signature,
        a: int,
        e: int,
        w: int,
        q: int,
        length: float,
        slack: float,
        near: float,
    ) -> int | None:
        """The rotation under which a meet point homed onto less than ``short_place_m``
        short of where edge ``e`` ends is ``w`` read at its place's other point: its length
        and clearance may be off by that much (the clearance changes by no more than the robot
        moves). fig16 seed 19, back from the indent's dead end, homed at the weak meet point
        0.31 m short of the corridor's, with the place's four edges and 0.89 m clear for
        1.15 m; taken for a weak meet point halfway, the robot went on through the place, up
        the corridor to the far junction, was lost there, and the place's three other edges
        were never explored. None if it is not."""
        rest = self.map.edge(e).length_m - length
        if not 0.0 < rest < self.p.short_place_m:
            return None
        k = self._match(ev, seen, a, w, q, length, length + rest, slack + rest, near + rest)
        if k is None:
            return None
        self._widen_span(w, rest)
        self.partial_m = 0.0
        self._note(f"node {w} read {rest:.2f} m short of its edge's end: its place's other point")
        return k

    def _expected(
        self, ev: MeetPointReached, seen: Signature, f: int, j: int, e: int, length: float | None
    ) -> tuple[int, int | PortMap]:
        slack = self.p.estimate_slack_m if e in self.estimated else 0.0
        edge = self.map.edge(e)
        w, q = edge.other_end(f, j)
        # A place read at both its points: the edge ends at one or the other, ...
        slack += self.span.get(f, 0.0) + self.span.get(w, 0.0)
        tol = self._tol(slack)
        a = ev.arrival_index
        assert a is not None
        # ... whose clearances differ by no more than the points lie apart (the distance to
        # the nearest obstacle changes by at most the distance moved): fig16's place, read
        # at the corridor's point 1.14 m clear, was not recognised at the weak one 0.89 m
        # clear with the same four edges, and the robot mapped it and the corridor again.
        near = self.span.get(w, 0.0) if self.p.place_span_clearance else 0.0
        k = self._match(ev, seen, a, w, q, length, edge.length_m, slack, near)
        back = k is None and self.map.node(f).kind == "boundary"
        bearings = self._back_by_bearings(ev, w, q) if back and self.p.back_by_bearings else None
        if bearings is not None and (
            bearings[0].index[q] != a or ev.degree != self.map.node(w).degree
        ):
            # The tracer took another departure for the way in: the rules below turned the
            # place's ports by one (fig16 seed 1) or found no rotation (seed 18); or two
            # edges were read as one, which the angle match below pairs by guesswork.
            return w, self._by_bearings(ev, f, w, *bearings)
        dead_end = back and self.map.node(w).degree == ev.degree
        # None when no recent pass can say; a twin junction a few decimetres on has the same
        # topology from a dead end.
        left_here = self._where_the_pass_left(ev, f, e) if back else None
        if dead_end and tol.length_ok(length, edge.length_m) and left_here is not False:
            # Back from a dead end there is one place to arrive at; only the signature's
            # noisier parts (clearance, a departure angle) disagree: trust the topology.
            k = (q - a) % ev.degree
            self._note(f"node {w} confirmed by topology alone (back from boundary {f})")
        elif left_here and dead_end:
            # One edge's length is off (the way in wandered at the corner), but the robot has
            # homed where it left for the dead end minutes ago, by dead reckoning over a few
            # metres: the same junction. The length is not recorded.
            self._note(f"node {w} confirmed by dead reckoning (back from boundary {f})")
            self.partial_m = 0.0
            return w, (q - a) % ev.degree
        elif left_here and (pm := self._read_where_left(ev, w, q)) is not None:
            # The same, read with an edge more or fewer: back from fig13's boundary 16 the
            # robot homed onto the other meet point of the 0.29 m pair it had read as one
            # place, whose edge to the pair's first point came in 40 degrees off the dead
            # end's, and the place went into the map twice (seed 1, switch hold_on).
            self._note(
                f"node {w} confirmed by dead reckoning (back from boundary {f}) although read "
                f"with degree {ev.degree}, not {self.map.node(w).degree}"
            )
            self.partial_m = 0.0
            self._misread = w
            return w, pm
        if k is not None:
            if length is not None and not self.disturbed:
                self.map.add_measurement(e, length)
                self.estimated.discard(e)
            self.partial_m = 0.0
            return w, k
        if bearings is not None:
            return w, self._by_bearings(ev, f, w, *bearings)
        askew = self._read_askew(ev, w, q, length, edge.length_m, slack)
        if askew is not None:
            if length is not None and not self.disturbed:
                self.map.add_measurement(e, length)
            self.partial_m = 0.0
            return w, askew
        # Dead reckoning that puts the robot elsewhere than where it left for the dead end
        # vetoes an arrival read askew (a twin junction, as above).
        turned = left_here is not False
        pm = self._read_otherwise(ev, w, q, length, edge.length_m, slack, turned=turned)
        if pm is not None:
            if length is not None and not self.disturbed:
                self.map.add_measurement(e, length)
            return self._as_read(ev, e, w, pm)
        short = length is not None and length < edge.length_m - tol.length_abs_m
        through = self._through_port(ev) if short else None
        if short and not self.disturbed:
            assert length is not None
            at = self._short_of_place(ev, seen, a, e, w, q, length, slack, near)
            if at is not None:
                return w, at
            split = None
            if self.p.split_open or through is None:
                split = self._missed_junction(ev, f, j, e, length)
            room = edge.length_m - length >= self.p.split_rest_m  # else the far end itself
            # Back from a dead end the way in was just traced: the pass says it, or nothing.
            room = room and self.map.node(f).kind == "meet"
            if split is None and room and self.p.split_open:
                split = self._junction_on_edge(ev, f, j, e, length)
            if split is not None:
                return split
            # The node read at its place's other point (``_short_of_place``) with an edge
            # more or fewer: fig16 seed 13 without drift, back from the indent's dead end,
            # homed at the weak meet point 0.36 m short of the corridor's with the place's
            # four edges; passed through as a weak meet point, the indent's other dead end
            # was never explored.
            rest = edge.length_m - length
            if 0.0 < rest < self.p.short_place_m and self.p.short_place_grow:
                pm = self._read_otherwise(
                    ev, w, q, length, edge.length_m, slack + rest, turned=turned
                )
                if pm is not None:
                    self._widen_span(w, rest)
                    return self._as_read(ev, e, w, pm)
        if through is not None:
            # A weak meet point halfway (section VII-B): it did not show when the edge was
            # first traced. Not a node of the map; the edge goes on straight ahead.
            self.partial_m = length
            self._through = through
            self._note(f"weak meet point passed on edge {e} ({f}-{w})")
            return f, 0
        # Homed past a weak meet point: one edge further than planned (section V-B). The
        # robot then came by w's edge, so the way back leads to w, whatever f is: back from
        # a dead end it is a meet point (fig13 seed 1: past meet point 8 to 9, and lost).
        # Only where no unexplored departure of w could have led to a look-alike instead:
        # back from fig15's corner the robot went through its junction along the aisle,
        # unexplored, to the next crossing, and was "recognised" one edge up the other aisle,
        # as long and alike (seed 2 on stop 44's tracer: a false merge). The walk below
        # follows the way's own turn there.
        found = []
        seen_past = self._seen(ev, a, w)
        ports = self.map.node(w).ports
        unknown_way = any(e2 is None for p, e2 in enumerate(ports) if p != q)
        for p, e2 in enumerate(ports):
            if e2 is None or p == q:
                continue
            e2d = self.map.edge(e2)
            w2, q2 = e2d.other_end(w, p)
            k2 = self._match(ev, seen_past, a, w2, q2, length, edge.length_m + e2d.length_m)
            if k2 is not None:
                found.append((w2, k2))
        if len(found) == 1 and not (unknown_way and self.p.further_known_only):
            self._note(f"expected node {w}, recognised node {found[0][0]} one edge further")
            self.partial_m = 0.0
            return found[0]
        went_otherwise = self._went_otherwise(ev, a, f, j, length, known=True)
        if went_otherwise is not None:
            return went_otherwise
        for back in (False, True):
            went = self._walked_to(ev, a, length, back)
            if went is not None:
                return went
        wn = self.map.node(w)
        why = (
            f"expected node {w} (degree {wn.degree}, clearance {wn.clearance_m:.2f} m) after "
            f"edge {e} ({edge.length_m:.2f} m), found degree {ev.degree}, clearance "
            f"{ev.clearance_m:.2f} m after {length or 0:.2f} m"
        )
        self._failed(f, j)
        return self._lost(ev, why)

    def _as_read(
        self, ev: MeetPointReached, e: int, w: int, pm: PortMap
    ) -> tuple[int, int | PortMap]:
        """Node ``w``, arrived at by edge ``e`` and read with an edge more or fewer (port map
        ``pm``); grown into its place where the edge it has more is one the map lacks."""
        self.partial_m = 0.0
        self._misread = w
        self._note(
            f"node {w} confirmed by edge {e} although read with degree {ev.degree}, "
            f"not {self.map.node(w).degree}"
        )
        # Each port on a departure of its own, or the reading says nothing of the place.
        distinct = len(set(pm.index)) == len(pm.index)
        grow = distinct and ev.degree > self.map.node(w).degree and not self._beside(w)
        if self.p.grow_place and grow:
            # The edge the reading has more is the place's, from its other point, which the
            # map has not seen: fig13 seed 3's 0.29 m pair, mapped from its west point, read
            # from the east with the east point's dead end besides; left out, the dead end
            # was never explored and the map never whole.
            grown = self._become_place(ev, w, dict(enumerate(pm.index)), ev.arrival_index)
            if grown is not None:
                self._misread = None
                return grown
        return w, pm

    def _match(
        self,
        ev: MeetPointReached,
        seen: Signature,
        a: int,
        w: int,
        q: int,
        length: float | None,
        mapped: float,
        slack_m: float = 0.0,
        clearance_slack_m: float = 0.0,
    ) -> int | None:
        """The rotation under which ``seen``, arrived at by index ``a``, is node ``w`` reached by
        its port ``q`` after an edge of ``mapped`` metres; None if it is not. Nor is it if
        that turns ``ev``'s departures further from ``w``'s than dead reckoning drifts: in
        fig12, whose junctions' departures are about evenly spread, a robot that went the
        wrong way round the triangle arrived along the other edge, after a length like the
        planned one, and was taken for arriving as planned, its map turned a third of a turn
        (seed 8). ``slack_m``: more slack on the length (``estimated``), ``clearance_slack_m``
        on the clearance."""
        pred = Prediction(w, q, mapped, self.map.node(w).kind)
        k = arrival_matches(self.map, seen, a, pred, length, self._tol(slack_m, clearance_slack_m))
        if k is None or self._odo is None:
            return k
        return k if self._turn_fits(ev.departures_rad, self._odo.distance_m, w, k) else None

    def _new_edge(
        self, ev: MeetPointReached, seen: Signature, f: int, j: int, length: float | None
    ) -> tuple[int, int | PortMap]:
        own = ev
        placed = self._as_predicted(ev, seen, f, j, length)
        if placed is not None:
            ev = placed.ev
            seen = self._seen(ev, placed.read.arrival, f)
        a = ev.arrival_index
        assert a is not None
        tol = self._tol()
        # What each open hypothesis predicted for this edge, checked before the map changes.
        survivors: list[Hypothesis] = []
        confirmed: list[tuple[Hypothesis, int, int]] = []
        past: list[tuple[Hypothesis, tuple[int, int] | None]] = []
        followed: list[tuple[Hypothesis, int, int]] = []
        for h in self.hyps.live:
            pred = predict(self.map, h, f, j)
            if pred is None:
                survivors.append(h)
                continue
            k = arrival_matches(self.map, seen, a, pred, length, tol)
            if placed is not None and pred.node != placed.node:
                k = None  # it did not fit the reading as it was (``_as_predicted``)
            # Two new nodes cannot both be one old place: the fragment is a walk through
            # places the robot had not seen since it left the map.
            fits = k is not None and all(c != pred.node for c, _ in h.mapping.values())
            if self.unsure_departure:
                # Left by a departure of a misread node: the arrival is no evidence (it may
                # be another look-alike as far), but where it fits, the hypothesis follows
                # the robot there, and the edges after it test it. Else it can say nothing
                # from here on and ages out (fig13 seed 56, at drift paper: the 0.29 m pair
                # read with an edge merged, left east to meet point 9, found as predicted).
                survivors.append(h)
                if fits and self.p.unsure_follow:
                    followed.append((h, pred.node, k))
            elif fits:
                survivors.append(h)
                confirmed.append((h, pred.node, k))
            elif k is None and self.p.cut_past:
                went = self._past_a_junction(h, pred, seen, a, length)
                if went is not None:
                    survivors.append(h)
                    past.append((h, went.beyond))
        alike = placed is None and not confirmed
        if alike and not self._past_as_read(ev, seen, f, a, length):
            placed = self._as_look_alike(ev)
            if placed is not None:
                ev = placed.ev
                a = placed.read.arrival
                assert a is not None
        node = self._add_meet(ev)
        if placed is not None:
            self._keep_own_reading(node, own, placed.read)
        edge = self.map.connect(f, j, node, a, 0.0 if length is None else length)
        lv = self._last_visit
        if lv is not None and lv[0] == f:
            self.edge_gap[edge] = math.hypot(ev.x_m - lv[3], ev.y_m - lv[4])
        for h, w, k in confirmed:
            h.mapping[node] = (w, k)
            if placed is None:  # a reading taken as the place predicted is no evidence
                h.confirmed += 1
        for h, w, k in followed:
            h.mapping[node] = (w, k)
        for h, went in past:
            if went is None:  # the old edge went past this junction
                pred = predict(self.map, h, f, j)
                assert pred is not None and pred.edge is not None
                h.cuts.add(pred.edge)
            else:  # this edge went past the predicted node to the one beyond
                h.cuts.add(edge)
                h.mapping[node] = went
        dropped = len(self.hyps.live) - len(survivors)
        spoke = {id(h) for h, _, _ in confirmed + followed} | {id(h) for h, _ in past}
        self.hyps.live = self._age(survivors, spoke)
        if self.hyps.live:
            self.hyps.fragment.add(node)
        # A node of the fragment that no open hypothesis places any more is a new place, as
        # it would be had the fragment closed (``close_fragment``): a candidate like any. A
        # fragment whose placement never settles, each new node bringing new look-alikes,
        # otherwise goes round a loop of the building for ever without closing onto itself.
        exclude = self.hyps.fragment | {node}
        if self.p.close_fragment:
            exclude = {x for h in self.hyps.live for x in h.mapping} & exclude | {node}
        fresh = candidates(self.map, self.map.signature(node), tol, exclude, a)
        # A look-alike some open hypothesis already maps this node to adds nothing: that
        # hypothesis says the same and more, and has the evidence.
        implied = {h.mapping[node] for h in self.hyps.live if node in h.mapping}
        fresh = [ck for ck in fresh if ck not in implied]
        if alike and placed is not None:
            fresh = [ck for ck in fresh if ck[0] == placed.node]
        crowd = self._crowd(node, fresh)
        for c, k in fresh:
            self.hyps.live.append(Hypothesis({node: (c, k)}, crowd=crowd))
        slips: list[tuple[int, int, int]] = []
        if self.p.past_candidates:
            sig, deps = self.map.signature(node), self.map.node(node).departures_rad
            read_at = self.born.get(node)
            slips = self._past_candidates(f, sig, deps, read_at, a, edge, length, {node})
        slips = [(c, k, e) for c, k, e in slips if (c, k) not in implied]
        for c, k, e in slips:
            self.hyps.live.append(Hypothesis({node: (c, k)}, crowd=crowd, cuts={e}))
        if fresh or slips:
            self.hyps.fragment.add(node)
        leads = self._lead_ins(f, j, node, a, length) if self.p.lead_ins else []
        leads = [h for h in leads if h.mapping[node] not in implied]
        reread = self._place_lead_ins(f, j, node, a, length) if self.p.place_lead_ins else []
        reread = [h for h in reread if h.mapping[node] not in implied]
        for h in leads + reread:
            self.hyps.live.append(h)
            self.hyps.fragment.add(node)
        if dropped or fresh or leads or reread or slips:
            self._note(
                f"node {node}: {len(fresh)} look-alike(s), "
                + (f"{len(slips)} if an edge went past a junction, " if slips else "")
                + (f"{len(leads)} if node {f} is mapped twice, " if leads else "")
                + (f"{len(reread)} if node {f} is a place read anew, " if reread else "")
                + f"{dropped} hypothesis(es) refuted, {len(self.hyps.live)} open"
            )
        self.partial_m = 0.0
        if placed is not None:
            why = "looks like" if alike else "is predicted to be"
            self._note(
                f"node {node}, read with {own.degree} edges, read as node {placed.node}, which"
                f" it {why}, with {ev.degree}"
            )
            return node, placed.read
        return node, 0

    def _past_a_junction(
        self, h: Hypothesis, pred: Prediction, seen: Signature, a: int, length: float | None
    ) -> Past | None:
        """A prediction that failed on its edge's length, explained by a junction passed
        without homing (section VII-B's weak meet points, a third wall the ring does not
        resolve): most wrong predictions of true hypotheses are that, and a refuted true
        hypothesis leaves the fragment a copy for good. Shorter than the map's edge: that
        edge went past the meet point just reached. Longer, or as long but not that node
        (``past_within_slack``): this traversal went past the predicted node, and reached
        the one beyond it that fits, alone, by signature and the two edges' length. None if
        neither, or if ``h`` already says ``MAX_CUTS`` other edges went past a junction: a
        repair or two is an explanation, more is a story.
        """
        if length is None or pred.edge is None:
            return None
        edge = self.map.edge(pred.edge)
        if edge.u in self.stored or edge.v in self.stored:
            # A stored map's edge was settled in an earlier run, and a restart may have
            # little else to place itself by: fig12 seed 4, killed after its first edge
            # (10.1 m) and restarted, cut that edge and never placed itself on the two
            # stored nodes (with ``cut_past`` on, fig12 seeds 1-6 killed after 1, 2, 3 and 5
            # edges: 19 restarts of 24 completed, 23 without cutting stored edges).
            return None
        if len(h.cuts) >= MAX_CUTS and pred.edge not in h.cuts:
            return None
        tol = self._tol()
        slack = tol.length_slack(pred.length_m)
        if length < pred.length_m - slack:
            return Past(None)
        # As long as the edge, but not the node predicted: the robot may have gone on past
        # it to a close pair's other point, a few decimetres further, within the length's
        # slack (fig13 seed 3 at drift none: 0.53 m past true meet point 3).
        within = length <= pred.length_m + slack + (tol.wandered_m if tol.at_least else 0.0)
        if within and not self.p.past_within_slack:
            return None
        if len(h.cuts) >= MAX_CUTS:
            return None
        w = self.map.node(pred.node)
        if w.kind != "meet":
            return None
        beyond = []
        for p, e2 in enumerate(w.ports):
            if e2 is None or p == pred.arrival_port:
                continue
            edge2 = self.map.edge(e2)
            w2, q2 = edge2.other_end(pred.node, p)
            two = Prediction(w2, q2, pred.length_m + edge2.length_m, self.map.node(w2).kind)
            k2 = arrival_matches(self.map, seen, a, two, length, tol)
            if k2 is not None and all(c != w2 for c, _ in h.mapping.values()):
                beyond.append((w2, k2))
        return Past(beyond[0]) if len(beyond) == 1 else None

    def _past_as_read(
        self, ev: MeetPointReached, seen: Signature, f: int, a: int, length: float | None
    ) -> bool:
        """Whether the reading as it is may be an old place the robot came to by an edge
        that went past a junction (``_past_candidates``). Then it is not read as a look-alike
        with an edge fewer instead: fig14 seed 1 without drift came east through the lab
        door's pair unhomed to the 0.29 m pair, read it with its four edges, and took it for
        the door's place mapped with three, turned some 30 degrees; the place it was, reached
        past the door, was never tested, and it was mapped five times."""
        if not (self.p.look_alike_past and self.p.past_candidates):
            return False
        read_at = None if self._odo is None else self._odo.distance_m
        deps = ev.departures_rad
        return bool(self._past_candidates(f, seen, deps, read_at, a, None, length, set()))

    def _past_candidates(
        self,
        f: int,
        seen: Signature,
        deps: tuple[float, ...],
        read_at: float | None,
        a: int,
        edge: int | None,
        length: float | None,
        exclude: set[int],
    ) -> list[tuple[int, int, int]]:
        """Old places a new node read as ``seen`` (arrived at by index ``a``, by ``edge`` if
        mapped yet) may be although the departure the robot came by is explored there, by
        an edge whose length says one of the two went past a junction without homing: (old
        node, rotation, the edge that went past). Longer than the length just measured: the
        old edge went past ``f``, the meet point just left (fig13: meet points 1 and 2 joined
        past meet point 0, which the robot then reached by its third edge). Shorter: the
        edge just traced went past the old edge's far end. The first tracing's look-alike is
        otherwise never a candidate, and the place is mapped again, with copies of
        everything beyond it. ``deps``, read at encoder distance ``read_at`` (None: not by
        the robot's encoders), must be turned from an old node's no further than dead
        reckoning's heading drifts; ``exclude``: nodes besides the fragment that are none."""
        if length is None or self.map.node(f).kind != "meet":
            return []
        tol = self._tol()
        alike = candidates(self.map, seen, tol, self.hyps.fragment | exclude, None)
        out = []
        for c, k in alike:
            pa = (a + k) % self.map.node(c).degree
            e = self.map.node(c).ports[pa]
            turned_ok = read_at is None or self._turn_fits(deps, read_at, c, k)
            if e is None or e == edge or not turned_ok:
                continue
            old = self.map.edge(e)
            slack = tol.length_slack(max(length, old.length_m))
            if length < old.length_m - slack:
                out.append((c, k, e))
            elif length > old.length_m + slack:
                far = old.other_end(c, pa)[0]
                if self.map.node(far).kind == "meet":
                    out.append((c, k, edge))
        return out

    def _crowd(self, node: int, fresh: list[tuple[int, int]]) -> int:
        """How many old places ``node`` may be, for the odds of each: its candidates, or,
        with ``crowd_all_ports``, every look-alike. A look-alike whose departure the robot
        came by is explored is not a candidate: that edge would have brought the robot there.
        But in a map that holds copies (a place mapped twice, the edge explored at one copy
        and not the other) that is no proof, and counting the candidates alone undercounts:
        fig1 seed 3 without drift, in a map of 193 nodes most of them copies, merged a room
        3.5 m west onto its twin on one confirmation and two dead ends, the only candidate
        of ten look-alikes."""
        if not self.p.crowd_all_ports:
            return len(fresh)
        alike = candidates(
            self.map, self.map.signature(node), self._tol(), self.hyps.fragment | {node}, None
        )
        return max(len(fresh), len(alike))

    def _lead_ins(
        self, f: int, j: int, node: int, a: int, length: float | None
    ) -> list[Hypothesis]:
        """Old places the new ``node`` may be although the edge that leads there is already
        mapped: node ``f``, just left by its unexplored port ``j``, may be the same place as
        an old node ``g`` whose port in that direction is explored, to ``c``. The robot, lost
        once, mapped a place again (fig12 seed 5: node 7 beside node 2); from then on every
        arrival by an edge only one of the two has explored is "new", since the old node
        that leads there is never a candidate, and the copies multiply. So where ``f`` or
        ``g`` had its look-alikes given up on (``doubtful``), the hypothesis maps ``f`` to
        ``g`` and ``node`` to ``c``. The edge just traced is tested as a prediction would be,
        but counts for nothing: the merge needs the usual proof from edges still to come.
        Two old places become one only if dead reckoning's heading fits both pairs, so
        without odometry (a mirror image in fig15 fits everything else) there are none."""
        if self.map.node(f).kind != "meet" or node not in self.born:
            return []
        tol = self._tol()
        seen = self.map.signature(node)
        taken = self.hyps.fragment | {f, node}
        out: list[tuple[int, int, int, int]] = []
        for g, kf in candidates(self.map, self.map.signature(f), tol, taken, None):
            pg = (j + kf) % self.map.node(g).degree
            e = self.map.node(g).ports[pg]
            if e is None or not {f, g} <= self.born.keys() or not {f, g} & self.doubtful:
                continue
            if not self._heading_fits(f, g, kf):
                continue
            led = self._lead_on(g, pg, node, seen, a, length, taken)
            if led is not None:
                out.append((g, kf, *led))
        crowd = max(len(out), self._crowd(node, []))
        return [Hypothesis({f: (g, kf), node: (c, k)}, crowd=crowd) for g, kf, c, k in out]

    def _lost(self, ev: MeetPointReached, why: str, resuming: bool = False) -> tuple[int, int]:
        """Not knowing where the robot came from, the node goes in unattached and every old
        node that looks like it is a hypothesis to test (``resuming``: against a stored map
        the robot restarted in)."""
        self._abandon_hypotheses(lost=True)
        node = self._add_meet(ev)
        tol = self.p.tol
        fresh = candidates(self.map, self.map.signature(node), tol, {node}, None)
        for c, k in fresh:
            self.hyps.live.append(
                Hypothesis(
                    {node: (c, k)}, lost_start=not resuming, resumed=resuming, crowd=len(fresh)
                )
            )
        if fresh:
            self.hyps.fragment.add(node)
        self.plan = []
        self.partial_m = 0.0
        self._note(f"lost ({why}): new node {node}, {len(fresh)} look-alike(s)")
        return node, 0

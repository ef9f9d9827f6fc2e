"""Junctions the robot went through without homing there: which way the recorded pass turned
(``tslam.core.walkon``), and so where it is.
"""

from __future__ import annotations

import math

from tslam.core.edgepaths import EdgePath
from tslam.core.explorer_state import ExplorerState, angdiff, nearest
from tslam.core.localize import Hypothesis, candidates
from tslam.core.portmap import PortMap, match_by_angle
from tslam.core.signature import rotations
from tslam.core.tracer import BoundaryReached, MeetPointReached
from tslam.core.walkon import Walk, walk_back, walk_on


class Unhomed(ExplorerState):
    """Placing the robot after a pass through an unhomed junction."""

    def _went_otherwise(
        self, ev: MeetPointReached, a: int, f: int, j: int, length: float | None, known: bool
    ) -> tuple[int, int] | None:
        """The node the robot came to if it left ``f`` by another departure than ``j`` and
        went one known edge, or two through a junction it did not home at: the one such
        node whose signature, arrival port, heading and the way's length all fit, if there
        is exactly one. In fig12 the robot meant to take the 10 m edge, went the other way
        round the triangle through a junction unhomed, and arrived after 10.3 m (seed 8).
        Only with dead reckoning's heading to check the rotation: the junctions of fig12
        look alike from every side. The way the robot went must also have left ``f`` by
        that departure (``_left_by``); if departure ``j`` was unexplored (``known`` False)
        the way must show it, for a new place reached by ``j`` is as likely."""
        if length is None or self._odo is None:
            return None
        left = self._left_by(f)
        if left == j or (left is None and not known):
            return None
        found: set[tuple[int, int]] = set()
        for p, e1 in enumerate(self.map.node(f).ports):
            if p == j or e1 is None or (left is not None and p != left):
                continue
            d1 = self.map.edge(e1)
            w1, q1 = d1.other_end(f, p)
            ways = [(w1, q1, d1.length_m, f)]
            through = self.map.node(w1).ports if self.map.node(w1).kind == "meet" else ()
            for p2, e2 in enumerate(through):
                if p2 == q1 or e2 is None:
                    continue
                d2 = self.map.edge(e2)
                w2, q2 = d2.other_end(w1, p2)
                ways.append((w2, q2, d1.length_m + d2.length_m, w1))
            for w, q, way_m, before in ways:
                if self.map.node(w).kind != "meet":
                    continue
                k = self._match(ev, self._seen(ev, a, before), a, w, q, length, way_m)
                if k is not None:
                    found.add((w, k))
        if len(found) != 1:
            return None
        ((w, k),) = found
        self._count_bounce((f, j), went_along_another=True)
        self._note(f"departure {j} of node {f} not held: went another way, recognised node {w}")
        self.partial_m = 0.0
        return w, k

    def _left_by(self, f: int) -> int | None:
        """The port of ``f``, the node just left, that the robot's recorded way went out by:
        the departure nearest the bearing to where the way is first ``left_by_m`` from the
        node, by dead reckoning over a metre or two, or, at a meet point reached sooner, to
        where the robot stands (``left_by_short_m``). None if the way does not say."""
        out = self._way_out(f, short=True)
        return None if out is None else nearest(*out)

    def _way_out(self, f: int, short: bool = False) -> tuple[float, list[float]] | None:
        """The bearing of the recorded way out of ``f`` (``_left_by``) and the bearing of each
        of ``f``'s ports as read on that visit, odometry frame; ``short``: to where the robot
        stands if the way is not ``left_by_m`` out."""
        lv, odo = self._last_visit, self._odo
        if lv is None or lv[0] != f or odo is None:
            return None
        path = self.paths.live(f, odo.distance_m)
        if path is None:
            return None
        _, deps, pm, x, y = lv
        reach, back = self.p.left_by_m, self.p.left_by_back_m
        points = [(u, v) for _, u, v in path.points]
        # Out and back through the node: the way out is the one after (fig13 seed 4, out
        # 0.9 m along a fourth edge true meet point 0 was once read with, back through it and
        # on along its edge south, to a place mapped again as new).
        near = [k for k, (u, v) in enumerate(points) if math.hypot(u - x, v - y) < back]
        points = points[near[-1]:] if near else points
        out = next(((u, v) for u, v in points if math.hypot(u - x, v - y) >= reach), None)
        # Arrived before the way was that far out: a close pair's short edge (fig13 seed 5:
        # out of true meet point 2 by the departure to a dead end, the robot swung onto the
        # 0.53 m edge to meet point 3, and mapped it again). Where it stands now says.
        least = self.p.left_by_short_m
        if out is None and short and least > 0.0 and math.hypot(odo.x_m - x, odo.y_m - y) >= least:
            out = (odo.x_m, odo.y_m)
        if out is None:
            return None
        ports = self._port_bearings_read(f, deps, pm) or [deps[i] for i in pm.index]
        return math.atan2(out[1] - y, out[0] - x), ports

    def _clearly_out_by(self, f: int, j: int) -> int | None:
        """The port of ``f`` other than ``j`` that the recorded way out is along, clearly
        nearer than ``j``'s (``departure_taken_margin_rad``); None if the way does not say."""
        out = self._way_out(f)
        if out is None:
            return None
        bearing, deps = out
        p = nearest(bearing, deps)
        off = angdiff(deps[p], bearing)
        if p == j or off + self.p.departure_taken_margin_rad > angdiff(deps[j], bearing):
            return None
        return p

    def _departure_taken(self, f: int, j: int) -> int:
        """The unexplored departure of ``f`` the robot went out by: ``j`` as planned, unless
        its recorded way out is clearly along another unexplored one. Leaving fig16's
        corridor junction for the indent, the trace law took the corridor's two walls 0.15 m
        out and went down the corridor; the edge was mapped as the indent's, and the robot
        went lost when it came back up by the corridor's departure (seed 4, switch vertex)."""
        p = self._clearly_out_by(f, j) if self.p.departure_taken else None
        if p is None or self.map.node(f).ports[p] is not None:
            return j
        self._note(f"departure {j} of node {f} not held: went out by departure {p}")
        self.leaving = (f, p)
        return p

    def _junction_on_edge(
        self, ev: MeetPointReached, f: int, j: int, e: int, length: float
    ) -> tuple[int, int]:
        """A junction partway along known edge ``e``, with no recent pass to say which of its
        departures leads on: the edge went past it. It goes into the map as a new node at
        the end of the stretch just traced, and the rest of ``e`` is forgotten: its far end's
        departure is to explore again, and so are the junction's. Which of them leads on is
        not guessed (straight on is not always it: fig1's meet point 8 turns 61 degrees).
        Before, the junction was passed as a weak meet point, no node of the map, and the
        branch beyond it was never mapped."""
        a = ev.arrival_index
        assert a is not None
        w = self.map.edge(e).other_end(f, j)[0]
        self._drop_placing_both(f, w)
        self.map.remove_edge(e)
        self.edge_gap.pop(e, None)
        self._note(
            f"a junction {length:.2f} m along edge {e} ({f}-{w}), which went past it: the edge "
            "is removed"
        )
        return self._new_edge(ev, self._seen(ev, a, f), f, j, length)

    def _drop_placing_both(self, f: int, w: int, keep: list[Hypothesis] | None = None) -> int:
        """Drop the hypotheses that placed both ends of an edge found to hold a junction:
        they placed the edge as one, which it is not (but those in ``keep``). Returns how
        many went."""
        spared = {id(h) for h in keep or ()}
        kept = [
            h
            for h in self.hyps.live
            if id(h) in spared or not (f in h.mapping and w in h.mapping)
        ]
        dropped = len(self.hyps.live) - len(kept)
        self.hyps.live = kept
        return dropped

    def _missed_junction(
        self, ev: MeetPointReached, f: int, j: int, e: int, length: float
    ) -> tuple[int, int] | None:
        """A junction partway along known edge ``e`` that its first tracing went by without
        homing: it goes into the map on the edge, which is split there, if the recorded pass
        shows which of its departures leads on to the edge's far end."""
        far = self._far_departure(ev, f, e, length)
        if far is None:
            return None
        a = ev.arrival_index
        assert a is not None
        w = self.map.edge(e).other_end(f, j)[0]
        node = self._add_meet(ev)
        near_e, far_e = self.map.split_edge(e, f, j, node, a, far, length)
        self._note(
            f"node {node} found {length:.2f} m along edge {e} ({f}-{w}), a junction its first "
            f"tracing went by: split into edges {near_e} and {far_e}"
        )
        kept = self._found_past(e, f, j, node, a, length) if self.p.past_found else []
        found = len(kept)
        dropped = self._drop_placing_both(f, w, kept)
        # It may be a junction already mapped from another side; both its known ports must
        # then be unexplored there.
        deg = ev.degree
        implied = {h.mapping[node] for h in self.hyps.live if node in h.mapping}
        fresh = [
            (c, k)
            for c, k in candidates(
                self.map, self.map.signature(node), self._tol(), self.hyps.fragment | {node}, a
            )
            if self.map.node(c).ports[(far + k) % deg] is None and (c, k) not in implied
        ]
        crowd = self._crowd(node, fresh)
        for c, k in fresh:
            self.hyps.live.append(Hypothesis({node: (c, k)}, crowd=crowd))
        if self.hyps.live:
            self.hyps.fragment.add(node)
        else:
            self.hyps.clear()
        if fresh or dropped or found:
            self._note(
                f"node {node}: {len(fresh)} look-alike(s), "
                + (f"{found} found the junction their edge went past, " if found else "")
                + f"{dropped} hypothesis(es) dropped, {len(self.hyps.live)} open"
            )
        self.partial_m = 0.0
        return node, 0

    def _found_past(
        self, e: int, f: int, j: int, node: int, a: int, length: float
    ) -> list[Hypothesis]:
        """The hypotheses that said edge ``e`` went past a junction, that junction found
        where they put it: ``node``, just split into ``e`` from ``f`` by its port ``a``, is
        the junction ``f``'s image leads to by the image of ``j``, as far as ``length``. Each
        maps ``node`` there, drops the cut, and counts a confirmation (a junction found
        where, and as, predicted). Before, they placed both ends of an edge that is no more,
        and were dropped with those that placed it as one (fig13 seed 2: past meet point 8
        to its dead end, the true hypothesis kept by the two edges' length, then dropped when
        the robot, back from the dead end, homed at the junction). Returns them."""
        seen = self.map.signature(node)
        tol = self._tol()
        found = []
        for h in self.hyps.live:
            img = h.image_port(self.map, f, j) if e in h.cuts else None
            if img is None or node in h.mapping:
                continue
            e1 = self.map.node(img[0]).ports[img[1]]
            if e1 is None:
                continue
            old = self.map.edge(e1)
            c, q = old.other_end(img[0], img[1])
            cn = self.map.node(c)
            if cn.kind != "meet" or cn.degree != seen.degree or c in h.mapping or any(
                x == c for x, _ in h.mapping.values()
            ):
                continue
            if not tol.length_ok(length, old.length_m):
                continue
            k = (q - a) % cn.degree
            if k not in rotations(seen, self.map.signature(c), tol.clearance_m, tol.angle_rad):
                continue
            h.mapping[node] = (c, k)
            h.cuts.discard(e)
            h.confirmed += 1
            h.silent_arrivals = 0
            found.append(h)
        return found

    def _read_where_left(self, ev: MeetPointReached, w: int, q: int) -> PortMap | None:
        """The port map of ``w``, read with another degree where the robot left it for a dead
        end moments ago: each port is the departure nearest its bearing as read then, both in
        the odometry frame (the heading drifts little over the way there and back). None
        unless the last visit was to ``w`` and every departure of the smaller reading but
        the arrival's has its counterpart within the angle tolerance."""
        lv, a = self._last_visit, ev.arrival_index
        if lv is None or lv[0] != w or a is None or self.map.node(w).kind != "meet":
            return None
        _, deps, pm, _, _ = lv
        tol = self._tol().angle_rad
        index, agree = [], 0
        for p, i in enumerate(pm.index):
            if p == q:
                index.append(a)
                continue
            k = min(
                (k for k in range(ev.degree) if k != a or ev.degree < len(pm.index)),
                key=lambda k: angdiff(ev.departures_rad[k], deps[i]),
            )
            index.append(k)
            agree += angdiff(ev.departures_rad[k], deps[i]) <= tol
        if agree < min(ev.degree, len(pm.index)) - 1:
            return None
        return PortMap(tuple(index), q)

    def _where_the_pass_left(self, ev: MeetPointReached, f: int, e: int) -> bool | None:
        """Whether the robot, back along edge ``e`` from ``f``, has homed where the recorded
        pass over ``e`` met its far node; None when there is no recent pass to say."""
        off = self._off_the_pass_end(ev, f, e)
        return None if off is None else off <= self.p.twin_m

    def _off_the_pass_end(
        self, ev: MeetPointReached | BoundaryReached, f: int, e: int
    ) -> float | None:
        """How far ``ev`` is from where the recorded pass over edge ``e`` met its far node
        from ``f``; None when there is no recent pass to say."""
        old = self._recent_pass(e)
        if old is None:
            return None
        x, y = old.at(old.length_m if old.start == f else 0.0)
        return math.hypot(ev.x_m - x, ev.y_m - y)

    def _recent_pass(self, e: int) -> EdgePath | None:
        """The recorded pass over edge ``e``, if the robot has travelled little since."""
        path, odo = self.paths.get(e), self._odo
        if path is None or odo is None:
            return None
        if odo.distance_m - path.end_distance_m > self.p.split_recent_m:
            return None
        return path.measured_as(self.map.edge(e).length_m)

    def _far_departure(self, ev: MeetPointReached, f: int, e: int, length: float) -> int | None:
        """Which departure of the meet point ``ev``, found ``length`` metres from node ``f``
        along edge ``e``, leads on along ``e``: from the recorded pass over ``e``."""
        p, a = self.p, ev.arrival_index
        path = self._recent_pass(e)
        if path is None or a is None:
            return None
        s, off = path.nearest(ev.x_m, ev.y_m)
        forward = path.start == f
        expect = length if forward else path.length_m - length
        if off > p.split_off_m or abs(s - expect) > p.split_slack_m:
            return None
        rest = path.length_m - s if forward else s
        if rest < (p.split_rest_unlike_m if self._unlike_far_end(ev, f, e) else p.split_rest_m):
            return None  # as likely the far end itself, read otherwise
        look = min(p.split_look_m, rest)
        on = s + look if forward else s - look
        tx, ty = path.at(on)
        bearing = math.atan2(ty - ev.y_m, tx - ev.x_m)
        fits = sorted(
            (angdiff(ev.departures_rad[i], bearing), i) for i in range(ev.degree) if i != a
        )
        if not fits or fits[0][0] > p.split_angle_rad:
            return None
        if len(fits) > 1 and fits[1][0] - fits[0][0] < p.split_margin_rad:
            return None
        return fits[0][1]

    def _unlike_far_end(self, ev: MeetPointReached, f: int, e: int) -> bool:
        """Whether the meet point ``ev`` cannot be edge ``e``'s far end from ``f`` read
        otherwise: the far end is a meet point whose clearance differs from the one read by
        more than the tolerance plus the far end's place span (``span``, if it was read
        at two points). Back from fig16's indent the weak meet point showed 0.4 m from the
        dead end, 0.45 m short of the corridor's junction (clearance 0.9 m against 1.14 m);
        passed through as no node, the indent's other dead end was never explored (seed 11
        without drift)."""
        edge = self.map.edge(e)
        w = edge.v if edge.u == f else edge.u
        far = self.map.node(w)
        slack = self.p.tol.clearance_m + self.span.get(w, 0.0)
        return far.kind == "meet" and abs(ev.clearance_m - far.clearance_m) > slack

    def _read_otherwise(
        self,
        ev: MeetPointReached,
        w: int,
        q: int,
        length: float | None,
        mapped: float,
        slack_m: float = 0.0,
        turned: bool = True,
    ) -> PortMap | None:
        """The port map if the meet point at the end of a known edge is its node read with
        one edge more or fewer (section VII-B's close meet points, a weak meet point): the
        edge's length agrees (only as a lower bound after a detour), so do the angles of all
        but the edge that differs, and so does the clearance, as far as two points of one
        place can differ: fig16's two are 0.91 m and 1.14 m clear, and its place, read at the
        weak one, was not recognised at the corridor's one. With ``turned``, the arrival edge
        may be read askew (``ExplorerParams.pair_turn_rad``)."""
        tol, wn = self._tol(slack_m), self.map.node(w)
        if (
            ev.arrival_index is None
            or self.partial_m > 0
            or length is None
            or wn.kind != "meet"
            or not tol.length_ok(length, mapped)
            or not self._one_place_clearances(ev.clearance_m, wn.clearance_m, tol)
        ):
            return None
        return match_by_angle(
            ev.departures_rad,
            ev.arrival_index,
            wn.departures_rad,
            q,
            tol.angle_rad,
            self.p.pair_turn_rad if turned else 0.0,
            self._turn_bound(w),
        )

    def _walk(self, length: float | None, back: bool) -> Walk | None:
        """Where the robot is if it went through the node it expected without homing there
        (``back``: through the node it had just left, the departure not held)."""
        if length is None or self.disturbed or self.leaving is None or self._odo is None:
            return None
        f, j = self.leaving
        path = self.paths.live(f, self._odo.distance_m)
        if path is None:
            return None
        walk = walk_back if back else walk_on
        return walk(self.map, f, j, path.measured_as(length), length, self._tol(), self.p.walk)

    def _walked_to(
        self, ev: MeetPointReached, a: int, length: float | None, back: bool
    ) -> tuple[int, int] | None:
        """The meet point ``ev`` placed by ``_walk``: a mapped node if the walk ends on one
        and the signature agrees, else a new node on the unexplored departure it ends on."""
        walk = self._walk(length, back)
        if walk is None:
            return None
        if walk.known:
            node = self.map.node(walk.node)
            e = node.ports[walk.port]
            assert e is not None
            before = self.map.edge(e).other_end(walk.node, walk.port)[0]
            k = self._match(ev, self._seen(ev, a, before), a, walk.node, walk.port, None, 0.0)
            if k is None:
                return None
            self._walked(walk, back, f"recognised node {walk.node}")
            self.partial_m = 0.0
            return walk.node, k
        self._walked(walk, back, f"a new edge from node {walk.node}")
        went = self._new_edge(ev, self._seen(ev, a, walk.node), walk.node, walk.port, walk.rest_m)
        self._estimated(walk.node, walk.port)
        return went

    def _walked_to_boundary(self, ev: BoundaryReached, length: float | None, back: bool) -> bool:
        """``_walked_to`` for a boundary point; whether it placed it."""
        walk = self._walk(length, back)
        if walk is None:
            return False
        if walk.known:
            if self.map.node(walk.node).kind != "boundary":
                return False
            self._walked(walk, back, f"recognised boundary {walk.node}")
            self.plan = []
            self._leave(walk.node, walk.port)
            return True
        self._walked(walk, back, f"a new edge from node {walk.node}")
        self.plan = []
        self._boundary_on_new_edge(ev, walk.node, walk.port, walk.rest_m)
        self._estimated(walk.node, walk.port)
        return True

    def _estimated(self, node: int, port: int) -> None:
        e = self.map.node(node).ports[port] if self.map.has_node(node) else None
        if e is not None:
            self.estimated.add(e)

    def _walked(self, walk: Walk, back: bool, found: str) -> None:
        self.paths.restart()  # the record is of no one edge
        passed = ", ".join(str(n) for n in walk.passed)
        if back:
            assert self.leaving is not None
            f, j = self.leaving
            self._count_bounce((f, j))
            self._note(
                f"departure {j} of node {f} not held: back through node(s) {passed} "
                f"without homing, {found}"
            )
        else:
            self._note(f"went through node(s) {passed} without homing (weak meet point), {found}")

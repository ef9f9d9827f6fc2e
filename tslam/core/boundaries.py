"""Boundary points (an edge's end where its two obstacles meet) as the robot reaches them.
"""

from __future__ import annotations

import math

from tslam.core.explorer_state import MAX_CUTS, ExplorerState
from tslam.core.localize import Hypothesis, Prediction, Tolerances, predict
from tslam.core.tracer import BoundaryReached


class Boundaries(ExplorerState):
    """Mapping a boundary-point arrival."""

    def _on_boundary(self, ev: BoundaryReached) -> None:
        length = self._edge_length(ev.edge_length_m)
        if self._short_from is not None:
            # A dead end on the way back from one short along a mapped edge: lost after all.
            self._short_from = None
            self.detoured = True
        if self.leaving is None or self.detoured:
            self._abandon_hypotheses(lost=True)
            b = self._add_boundary(ev)
            self._leave(b, 0)
            return
        f, j = self.leaving
        e = self.map.node(f).ports[j]
        if e is not None:
            edge = self.map.edge(e)
            w, q = edge.other_end(f, j)
            if self.map.node(w).kind == "boundary" and self._dead_end_tol(ev, w).length_ok(
                length, edge.length_m
            ):
                if length is not None and not self.disturbed:
                    self.map.add_measurement(e, length)
                self._leave(w, q)
                return
            if self._boundary_bounce(ev, f, j, length):
                return
            if self._walked_to_boundary(ev, length, False) or self._walked_to_boundary(
                ev, length, True
            ):
                return
            if self._short_end(ev, f, j, e, length):
                return
            self._failed(f, j)
            self._abandon_hypotheses(lost=True)
            self.plan = []
            b = self._add_boundary(ev)
            self._note(f"expected node {w} after edge {e}, found a boundary: node {b}")
            self._leave(b, 0)
            return
        if self._walked_to_boundary(ev, length, back=True) or self._boundary_again(
            ev, f, j, length
        ):
            return
        self._boundary_on_new_edge(ev, f, self._departure_taken(f, j), length)

    def _dead_end_tol(self, ev: BoundaryReached, b: int) -> Tolerances:
        """The length tolerance for an edge that ends at boundary ``b`` reached again as
        ``ev``: the edge ends where the boundary rule stopped the robot, and stopped nearer the
        walls (the gap pinching, not the corner ahead) it went deeper in, by about half as far
        again as it came nearer in a right-angled corner. fig1 restarted in its top right room
        reached a dead end 0.68 m out, mapped 0.40 m out, and its true placement was refuted
        (seed 2)."""
        nearer = abs(ev.clearance_m - self.map.node(b).clearance_m)
        return self._tol(self.p.dead_end_depth * nearer)

    def _boundary_again(self, ev: BoundaryReached, f: int, j: int, length: float | None) -> bool:
        """Sent out by unexplored departure ``j`` of junction ``f``, the robot went out by
        a mapped one to a dead end and arrived there again: the length agrees, and dead
        reckoning puts it where the robot has just been, or the way out is along that
        departure and dead reckoning does not say otherwise. Then it is that boundary, and
        ``j`` is still to explore. Mapped as a second boundary of ``f`` at the same corner,
        it let a merge pair that node with a look-alike 1.6 m away (fig14 seed 2 at drift
        paper with the switch ``recess``, 12845 s: a false merge); and fig1's room corner
        (seed 6 without drift, switch hold_on, 477 s) went into the map twice, reached 3 cm
        from where it had been 16 s before, the way out halfway between two departures."""
        if self.map.node(f).kind != "meet":
            return False
        # A place's dead ends were reached from either of its points.
        along, tol, p = self._clearly_out_by(f, j), self._tol(self.span.get(f, 0.0)), self.p
        for k, e in enumerate(self.map.node(f).ports):
            if k == j or e is None:
                continue
            edge = self.map.edge(e)
            b, q = edge.other_end(f, k)
            if self.map.node(b).kind != "boundary" or not tol.length_ok(length, edge.length_m):
                continue
            off = self._off_the_pass_end(ev, f, e)
            if (off is not None and off <= p.boundary_same_m) or (
                k == along and (off is None or off <= p.boundary_again_m)
            ):
                self._count_bounce((f, j), went_along_another=True)
                self._note(
                    f"departure {j} of node {f} not held: went out by departure {k}, back at "
                    f"boundary {b}"
                )
                self.plan = []
                self._leave(b, q)
                return True
        return False

    def _boundary_bounce(self, ev: BoundaryReached, f: int, j: int, length: float | None) -> bool:
        """Back in the corner just left, moments later (the edge out of it was not held):
        the same boundary point, by dead reckoning over the last metre. The robot tries its
        way out once more rather than mapping the corner twice."""
        p, odo = self.p, self._odo
        here = None if odo is None else self.paths.live(f, odo.distance_m)
        if (
            self.map.node(f).kind != "boundary"
            or here is None
            or length is None
            or length > p.bounce_length_m
            or math.hypot(ev.x_m - here.points[0][1], ev.y_m - here.points[0][2]) > p.bounce_m
            or self.bounces.get((f, j), 0) > p.bounce_retries
        ):
            return False
        self.bounces[(f, j)] = self.bounces.get((f, j), 0) + 1
        self._note(f"back at boundary {f}: the edge out of it could not be held")
        self._leave(f, j)
        return True

    def _boundary_on_new_edge(
        self, ev: BoundaryReached, f: int, j: int, length: float | None
    ) -> None:
        survivors = []
        confirmed = []
        past = []
        for h in self.hyps.live:
            pred = predict(self.map, h, f, j)
            if pred is None or self.unsure_departure:
                survivors.append(h)
            elif pred.kind == "boundary" and self._dead_end_tol(ev, pred.node).length_ok(
                length, pred.length_m
            ):
                survivors.append(h)
                confirmed.append((h, pred.node))
            elif (beyond := self._past_to_dead_end(h, pred, ev, length)) is not None:
                survivors.append(h)
                past.append((h, beyond))
        b = self._add_boundary(ev)
        edge = self.map.connect(f, j, b, 0, 0.0 if length is None else length)
        for h, w in confirmed:
            h.mapping[b] = (w, 0)
            h.dead_ends += 1
        for h, w in past:
            h.mapping[b] = (w, 0)
            h.cuts.add(edge)
        refuted = len(self.hyps.live) - len(survivors)
        spoke = {id(h) for h, _ in confirmed} | {id(h) for h, _ in past}
        survivors = self._age(survivors, spoke)
        if refuted:
            # Said, as at a meet point: a hypothesis that vanished at a dead end unnoted left
            # a progress log of look-alikes none of which was ever refuted.
            self._note(
                f"boundary {b}: {refuted} hypothesis(es) refuted, {len(survivors)} open"
            )
        self.hyps.live = survivors
        if survivors:
            self.hyps.fragment.add(b)
        else:
            self.hyps.clear()
        self._leave(b, 0)

    def _past_to_dead_end(
        self, h: Hypothesis, pred: Prediction, ev: BoundaryReached, length: float | None
    ) -> int | None:
        """The dead end beyond the meet point ``h`` predicted, if the robot went past that
        junction without homing and on to it: the one boundary, off another of its ports,
        that the two edges' length reaches (as ``Arrival._past_a_junction`` finds a meet
        point beyond). fig13 seed 2 went east from meet point 7 past meet point 8 unhomed, to
        its dead end 3.2 m on; the true hypothesis, which said meet point 8 at 2.0 m, was
        refuted there, and the building was mapped again. None if there is no such dead end,
        or more than one, or ``h`` already says ``MAX_CUTS`` edges went past a junction."""
        if not (self.p.cut_past and self.p.past_to_dead_end) or length is None:
            return None
        if pred.kind != "meet" or len(h.cuts) >= MAX_CUTS or pred.node in self.stored:
            return None
        tol = self._tol()
        if length <= pred.length_m + tol.length_slack(pred.length_m):
            return None
        beyond = []
        for p, e in enumerate(self.map.node(pred.node).ports):
            if e is None or p == pred.arrival_port:
                continue
            edge = self.map.edge(e)
            b, _ = edge.other_end(pred.node, p)
            if self.map.node(b).kind != "boundary" or any(c == b for c, _ in h.mapping.values()):
                continue
            if self._dead_end_tol(ev, b).length_ok(length, pred.length_m + edge.length_m):
                beyond.append(b)
        return beyond[0] if len(beyond) == 1 else None

"""A dead end reached short along a mapped edge that leads to a junction: the robot did not
hold the edge (or read a doorway's jamb as a corner), so it goes back to the junction it just
left, recognises it there by dead reckoning over the few metres out and back, and tries the
departure again, instead of taking itself for lost.

fig14 seed 1 without drift (1050 s): leaving the lab's junction for its door, the robot went
on straight 0.24 m west of the door's line and stopped at the jamb 1.45 m out on the mapped
2.93 m edge. Taken for lost, it mapped the junction again with that dead end; the copy looked
otherwise than the junction, so the proven merge of the lab's far side was refused, and the
lab's copies multiplied until the run's time was out.
"""

from __future__ import annotations

import math

from tslam.core.explorer_state import ExplorerState
from tslam.core.portmap import PortMap, bearing_shift
from tslam.core.tracer import BoundaryReached, MeetPointReached


class ShortEnds(ExplorerState):
    """Going back from a dead end short along a mapped edge (``ExplorerParams.short_end_back``)."""

    def _short_end(
        self, ev: BoundaryReached, f: int, j: int, e: int, length: float | None
    ) -> bool:
        """Whether the dead end ``ev``, ``length`` out by port ``j`` of meet node ``f`` along
        mapped edge ``e`` to a junction, is taken for an edge not held: the robot goes back
        to ``f`` (``_back_from_short_end``), as often as ``bounce_retries`` allows. Or, if the
        way out was clearly along an unexplored departure of ``f``, the dead end is that
        departure's, mapped so."""
        p, lv = self.p, self._last_visit
        if not p.short_end_back or length is None or self.disturbed:
            return False
        if lv is None or lv[0] != f or self.map.node(f).kind != "meet":
            return False
        edge = self.map.edge(e)
        w, _ = edge.other_end(f, j)
        if self.map.node(w).kind != "meet" or self.bounces.get((f, j), 0) >= p.bounce_retries:
            return False
        if length >= edge.length_m - self._tol().length_slack(edge.length_m):
            return False
        other = self._clearly_out_by(f, j)
        if other is not None:
            if self.map.node(f).ports[other] is not None:
                return False
            # Out by another departure, not yet explored: its dead end (fig14 seed 16 at drift
            # severe came back in by it, was taken for homed short along the edge, and the
            # edge was dropped as one that went past a junction).
            self._boundary_on_new_edge(ev, f, self._departure_taken(f, j), length)
            return True
        self._count_bounce((f, j))
        self._short_from = (f, j, length)
        # The way out and back is no pass over the edge (``_leave`` records one).
        self.paths.restart()
        self._note(
            f"expected node {w} after edge {e} ({edge.length_m:.2f} m), found a dead end "
            f"{length:.2f} m out: back to node {f} to try again"
        )
        return True

    def _back_from_short_end(
        self, ev: MeetPointReached, short: tuple[int, int, float] | None
    ) -> tuple[int, PortMap] | None:
        """Node ``f``, homed onto again back from a dead end short along its edge (``short``,
        from ``_short_end``): about as far back as out, where dead reckoning left it, about
        as clear, by the port it left by; its ports by their bearings, in the odometry frame
        as when it was left (a few metres of travel turn that little). None otherwise: then
        it is a bounce (``Arrival._bounced``) or the robot is lost."""
        lv, a, p = self._last_visit, ev.arrival_index, self.p
        if short is None or lv is None or a is None or ev.edge_length_m is None:
            return None
        f, j, out_m = short
        node, deps, pm, x, y = lv
        if node != f or self.leaving != (f, j) or not self.map.has_node(f):
            return None
        span = self.span.get(f, 0.0)
        tol = self._tol(span)
        reach = max(p.bounce_m + p.bounce_rel * 2.0 * out_m, p.bounce_place_m, span)
        if math.hypot(ev.x_m - x, ev.y_m - y) > reach or not tol.length_ok(ev.edge_length_m, out_m):
            return None
        if abs(ev.clearance_m - self.map.node(f).clearance_m) > tol.clearance_m:
            return None
        if ev.degree == len(deps):
            shift = bearing_shift(ev.departures_rad, deps, p.bounce_angle_rad)
            if shift is None:
                return None
            back = pm.shifted_events(shift, ev.degree)
            if back.index[j] != a:
                return None
            found = PortMap(back.index, j)
        else:
            found = self._read_where_left(ev, f, j)
            if found is None:
                return None
        self._note(f"back at node {f} from the dead end: departure {j} could not be held")
        self._no_pass = True
        return f, found

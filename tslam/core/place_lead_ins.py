"""Lead-ins from a place mapped again because it was read with an edge more or fewer.

A close pair of meet points is one junction to a sonar robot, read with three edges on one
visit and four on another (merge_grow.py). Reached by an edge its first reading lacked, such
a place has no look-alike (another degree), so it goes into the map as a new node; and from
that copy every arrival looks new too, since the old node that leads on has that edge explored
already. fig14 seed 1 read the lab's 0.26 m pair by the south door with three edges as its
first node, came back up from the door at 887 s, read it with four, and mapped it again;
the east table's pair, reached from the copy 3.87 m on, went in again as well (the old pair
node's edge of 3.86 m to it was explored), and the copies multiplied from there.

So a new node reached from such a node ``f`` (like no other node as read, and one edge more
or fewer than an old node ``g``'s, the rest agreeing in angle under a turn within dead
reckoning's heading drift, as ``ports_in_place`` reads it) is also tested as the place
``g``'s edge that way leads to. The hypothesis names the new node only: ``f`` and ``g``
differ in degree, so no rotation makes one the other; the merge's zipping reaches them by
the edge it makes one, and reads the node with fewer edges again as its place
(``MergeGrow``). As for a lead-in, the edge just traced counts for nothing: the merge needs
the usual proof from edges still to come.
"""

from __future__ import annotations

from tslam.core.explorer_state import ExplorerState
from tslam.core.localize import Hypothesis, Prediction, arrival_matches, candidates
from tslam.core.merge_grow import ports_in_place
from tslam.core.signature import Signature


class PlaceLeadIns(ExplorerState):
    """Lead-in hypotheses from a node that may be an old place read with another degree."""

    def _place_lead_ins(
        self, f: int, j: int, node: int, a: int, length: float | None
    ) -> list[Hypothesis]:
        """Old places the new ``node`` (arrived at by index ``a`` after ``length`` metres) may
        be, reached from ``f`` by its port ``j``, ``f`` being an old node's place read with an
        edge more or fewer."""
        fn = self.map.node(f)
        if fn.kind != "meet" or f not in self.born or node not in self.born:
            return []
        tol = self._tol()
        if candidates(self.map, self.map.signature(f), tol, {f}, None):
            # A reading like some other place's is no misread: in fig15, where junctions of
            # three edges and of four stand alike along the walls and between the blocks,
            # every node looked like some place read with an edge more or fewer, and the
            # ambiguity, reported at 959 s without these lead-ins, waited until 1433 s.
            return []
        seen = self.map.signature(node)
        taken = self.hyps.fragment | {f, node}
        found: set[tuple[int, int]] = set()
        for g in self.map.nodes():
            if (
                g.kind != "meet"
                or g.id in taken
                or g.id not in self.born
                or abs(g.degree - fn.degree) != 1
                or g.ambiguous_with
                or not self._one_place_clearances(g.clearance_m, fn.clearance_m, tol)
            ):
                continue
            bound = self._heading_drift(abs(self.born[f] - self.born[g.id]))
            for pg in same_port(fn.departures_rad, j, g.departures_rad, tol.angle_rad, bound):
                led = self._lead_on(g.id, pg, node, seen, a, length, taken)
                if led is not None:
                    found.add(led)
        crowd = max(len(found), self._crowd(node, []))
        return [Hypothesis({node: (c, k)}, crowd=crowd) for c, k in sorted(found)]

    def _lead_on(
        self,
        g: int,
        pg: int,
        node: int,
        seen: Signature,
        a: int,
        length: float | None,
        taken: set[int],
    ) -> tuple[int, int] | None:
        """Where old node ``g``'s explored port ``pg`` leads, as the new ``node`` (read as
        ``seen``, arrived at by index ``a`` after ``length`` metres) would be it: (that meet
        node, rotation); None if the port is unexplored, its far end is in ``taken`` or no
        meet node the robot read, or the arrival does not fit it."""
        e = self.map.node(g).ports[pg]
        if e is None:
            return None
        edge = self.map.edge(e)
        c, q = edge.other_end(g, pg)
        if c in taken or self.map.node(c).kind != "meet" or c not in self.born:
            return None
        pred = Prediction(c, q, edge.length_m, "meet")
        k = arrival_matches(self.map, seen, a, pred, length, self._tol())
        return (c, k) if k is not None and self._heading_fits(node, c, k) else None


def same_port(
    deps: tuple[float, ...], j: int, other: tuple[float, ...], tol_rad: float, bound_rad: float
) -> list[int]:
    """The ports of a reading ``other`` of a place that port ``j`` of the reading ``deps``
    may be, the two readings one departure apart (``ports_in_place``)."""
    if len(deps) + 1 == len(other):
        return [
            py
            for py in range(len(other))
            if ports_in_place(deps, j, other, py, tol_rad, bound_rad) is not None
        ]
    if len(deps) == len(other) + 1:
        return [
            px
            for px in range(len(other))
            if ports_in_place(other, px, deps, j, tol_rad, bound_rad) is not None
        ]
    return []

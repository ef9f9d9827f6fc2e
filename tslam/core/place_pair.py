"""Two nodes a short edge apart, each read as the same place, made one node.

A close pair of meet points is one junction to a sonar robot (section VII-B; place.py), but
the robot does not always home onto the same point of it: fig16's corridor meet point and the
weak one 0.36 m into the indent were each mapped as a node of degree four, joined by an edge
of their own, with the four edges of the place on both. Each then led out along the same
corridors, and everything beyond was mapped twice (fig16 seed 6 at drift paper: the south
end's meet point and both its dead ends). No hypothesis tests this: both nodes are old, and
the edge between them was traced, not predicted.

So where the robot stands on a meet node joined by an edge no longer than
``ExplorerParams.pair_contract_m`` to another meet node, and each port of the one with fewer
edges (or of either) agrees in absolute bearing with a port of its own of the other, but for
the one to it on a node read with an edge fewer (fig16 seed 9: the weak meet point read
alone, the place read at the corridor's point), the edge between them goes and the two become
one node: the place, its ports the union of theirs. The robot read both from a few
decimetres apart, so dead reckoning's heading has not turned between them. Whatever
the topology then forces (the same corridor mapped from both) merges too, each pair tested
as every merge is (``TopoMap.merge`` with the likeness a prediction must show), or nothing
changes. Not while a hypothesis is open: its mapping names the nodes.
"""

from __future__ import annotations

from dataclasses import replace

from tslam.core.explorer_state import ExplorerState, angdiff, nearest
from tslam.core.portmap import PortMap
from tslam.core.topomap import MapError, TopoMap
from tslam.core.tracer import MeetPointReached
from tslam.core.zipmerge import Renames, merge_mapping


class PlacePair(ExplorerState):
    """Contracting a close pair mapped as two nodes of one place."""

    def _contract_pair(
        self, ev: MeetPointReached, here: int, pm: PortMap
    ) -> tuple[int, PortMap] | None:
        """Merge ``here`` (read as ``pm`` says) and a node one short edge away that reads as
        part of the same place into the older of the two; where the robot then stands, or
        None if nothing merged."""
        if self.p.pair_contract_m <= 0.0 or self.hyps.live or not self.map.has_node(here):
            return None
        node = self.map.node(here)
        if node.kind != "meet" or node.ambiguous_with or self._in_hypotheses(here):
            return None
        for p, e in enumerate(node.ports):
            if e is None:
                continue
            edge = self.map.edge(e)
            w, q = edge.other_end(here, p)
            other = self.map.node(w)
            if (
                w == here
                or other.kind != "meet"
                or edge.length_m > self.p.pair_contract_m
                or other.ambiguous_with
                or self._in_hypotheses(w)
            ):
                continue
            # The place is the reading with more edges (of two alike, the older node's);
            # the other point's ports are among them, but for the one the edge between the
            # two leaves by.
            roles = [(here, w, q), (w, here, p)]
            roles.sort(key=lambda r: (-self.map.node(r[0]).degree, r[0]))
            for place, point, inner in roles:
                carry = self._ports_within(place, point, inner)
                if carry is None:
                    continue
                deps = self.map.node(place).departures_rad
                renamed = self._contract(place, point, e, carry, edge.length_m)
                if not renamed:
                    continue
                if here == place:
                    return self._stand(ev, here, pm, renamed)
                # The robot stands at the point: each of the place's ports is the departure
                # its port was read as, or the one nearest its bearing; it came in by the
                # port its way in went to, or from inside the place.
                index = [
                    next((pm.index[j] for j, k in carry.items() if k == port), None)
                    for port in range(len(deps))
                ]
                near = [
                    i if i is not None else nearest(b, ev.departures_rad)
                    for i, b in zip(index, deps, strict=True)
                ]
                came = pm.arrival
                moved = PortMap(tuple(near), None if came in (None, inner) else carry.get(came))
                return self._stand(ev, here, moved, renamed)
        return None

    def _ports_within(self, place: int, point: int, inner: int) -> dict[int, int] | None:
        """Port ``j`` of ``point`` -> the port of ``place`` with its bearing, each a port of
        its own; None if some port has none, or ``place`` has fewer ports than ``point``.
        Read with fewer edges than the place, ``point``'s port ``inner`` (to the place's
        other point) may have none: the place has no departure there."""
        a, b = self.map.node(place), self.map.node(point)
        if a.degree < b.degree:
            return None
        tol = self.p.tol.angle_rad
        out: dict[int, int] = {}
        for j, bearing in enumerate(b.departures_rad):
            k = min(range(a.degree), key=lambda i: angdiff(a.departures_rad[i], bearing))
            if angdiff(a.departures_rad[k], bearing) <= tol and k not in out.values():
                out[j] = k
            elif j != inner or b.degree == a.degree:
                return None
        return out

    def _contract(
        self, place: int, point: int, e: int, carry: dict[int, int], length: float
    ) -> Renames:
        """Remove edge ``e`` between them, read ``point`` as ``place`` (its port ``j`` is
        port ``carry[j]``) and merge the two into the older, on a copy first: the map
        changes only if the merge holds."""
        a, b = self.map.node(place), self.map.node(point)
        # Each point's clearance differs from the other's by at most the edge between them;
        # the place's lies between (``Arrival._become_place``).
        clearance = 0.5 * (a.clearance_m + b.clearance_m)
        same = {j: j for j in range(a.degree)}
        keep, drop = min(place, point), max(place, point)
        # An edge of the place was measured from one point or the other: two measurements
        # of one edge differ by up to the edge between the points.
        base = self._likeness()
        alike = replace(base, length_abs_m=base.length_abs_m + length)

        def prepare(tmap: TopoMap) -> None:
            tmap.remove_edge(e)
            explored = {j: k for j, k in carry.items() if tmap.node(point).ports[j] is not None}
            tmap.reread(point, a.departures_rad, clearance, explored)
            tmap.reread(place, a.departures_rad, clearance, same)

        mapping = {drop: (keep, 0)}
        trial = self.map.copy()
        try:
            prepare(trial)
            merge_mapping(trial, mapping, alike)
        except MapError:
            return {}
        self.edge_gap.pop(e, None)
        prepare(self.map)
        renamed, merged = self._merge_recorded(mapping, alike)
        if self.p.place_span_slack:
            # Its edges were measured from one point or the other (``Arrival._spans``).
            spans = (self.span.pop(place, 0.0), self.span.pop(point, 0.0), length)
            self.span[keep] = max(spans)
        self._note(
            f"nodes {place} and {point}, {length:.2f} m apart, read as one place: "
            + ", ".join(f"{d}={r}" for d, r, _, _ in merged.pairs)
            + f"; {self._size()}"
        )
        self._apply_renames(renamed)
        return renamed

"""A merge that makes one place of two readings of it, one with an edge fewer.

A close pair of meet points (section VII-B) is one junction to a sonar robot, but not every
reading of it shows all its edges: fig14's two pairs (0.26 m by the lab door, 0.29 m by the
east table) are read with three edges on one visit and four on another, and a proven
hypothesis whose zipping reached the two readings was refused for their degrees ("would make
meet 32 (degree 4) the same place as meet 18 (degree 3)"), its fragment left a copy for good.

So where a merge reaches two meet nodes by one edge it makes one, their degrees one apart,
the node with fewer edges is read again as the other reads the place (``_grow``), and the
merge is tried once more. Each port of the node with fewer edges goes to a departure of its
own of the other, the edge they are reached by to the edge's, the rest in the order of their
bearings; every one agrees in angle under one turn within dead reckoning's heading drift
between the two readings, but that one may be two edges read as one, lying between them
(``ports_in_place``). The departure it lacked becomes unexplored, as a place read anew with
an edge more does (``ExplorerParams.grow_place``). Not a node a live hypothesis names: its
ports are what the hypothesis's rotation refers to; nor a stored map's.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from tslam.core.explorer_state import ExplorerState, angdiff
from tslam.core.frames import TAU
from tslam.core.localize import Hypothesis
from tslam.core.topomap import TopoMap

#: Nodes one merge may read again so: fig14 has two such pairs.
MAX_GROWS = 2
#: Two edges read as one departure read it between them, to within this.
MERGED_SLACK_RAD = math.radians(10.0)


class MergeGrow(ExplorerState):
    """Reading a node with an edge fewer as its place, for a merge that needs it."""

    def _grow(
        self,
        view: TopoMap,
        ends: tuple[tuple[int, int], tuple[int, int]],
        h: Hypothesis | None = None,
        keep: Sequence[Hypothesis] = (),
    ) -> tuple[int, tuple[float, ...], float, dict[int, int]] | None:
        """The node of ``ends`` with fewer edges read as the other reads the place: (node,
        departures, clearance, carry); None if it does not read so. ``ends``: the (node,
        port) each is reached by through the edge the merge makes one; ``h``: the hypothesis
        merged, ``keep``: those its merge keeps open (``_outlives``)."""
        (x, px), (y, py) = ends
        if view.node(x).degree > view.node(y).degree:
            (x, px), (y, py) = (y, py), (x, px)
        low, high = view.node(x), view.node(y)
        named = self._in_hypotheses(x) if h is None else self._outlives(x, h, keep)
        if x in self.stored or low.ambiguous_with or named:
            return None
        tol = self._tol()
        if not self._one_place_clearances(low.clearance_m, high.clearance_m, tol):
            return None
        bx, by = self.born.get(x), self.born.get(y)
        bound = math.pi if bx is None or by is None else self._heading_drift(abs(bx - by))
        read = ports_in_place(
            low.departures_rad,
            px,
            high.departures_rad,
            py,
            tol.angle_rad,
            bound,
            view.signature(x).to_boundary,
            view.signature(y).to_boundary,
        )
        if read is None:
            return None
        turn, to = read
        # The other's reading turned into this node's frame, in order of bearing.
        turned = [(d - turn) % TAU for d in high.departures_rad]
        order = sorted(range(high.degree), key=lambda i: turned[i])
        at = {i: order.index(i) for i in range(high.degree)}
        carry = {p: at[to[p]] for p in range(low.degree)}
        return x, tuple(turned[i] for i in order), low.clearance_m, carry

    def _outlives(self, x: int, h: Hypothesis, keep: Sequence[Hypothesis]) -> bool:
        """Whether ``h`` or a hypothesis that may outlive its merge names ``x``: its rotation
        refers to ``x``'s ports. The merge drops every other live hypothesis that shares a
        node with ``h`` (``Resolving._merge``, ``_apart_from``), so one of those naming
        ``x`` does not keep it from being read again: in fig14 seed 14 at drift paper, a
        rival naming the junction by the lab's east wall, read there with an edge fewer,
        refused a merge proven seven times over, and its fragment of 16 nodes stayed copies.
        """
        mine = h.named
        for o in self.hyps.live:
            names = o.named
            if x not in names:
                continue
            if o is h or any(o is k for k in keep) or not names & mine:
                return True
        return x in mine

    def _apply_grows(self, h: Hypothesis) -> None:
        """Read the nodes ``h``'s merge needed read again (``Hypothesis.grows``) so."""
        for n, deps, clearance, carry in current_grows(self.map, h):
            was = self.map.node(n).degree
            if self.leaving is not None and self.leaving[0] == n:
                self.leaving = (n, carry[self.leaving[1]])
            self._reread_node(n, deps, clearance, carry)
            self._note(f"node {n}, read with {was} edges, read as its place with {len(deps)}")


def current_grows(
    tmap: TopoMap, h: Hypothesis
) -> list[tuple[int, tuple[float, ...], float, dict[int, int]]]:
    """``h``'s readings again (``Hypothesis.grows``) that still fit ``tmap``: they were worked
    out for the map as it stood at the merge's last try, and a node since merged away or
    read again is left as it is."""
    return [
        (n, deps, clearance, carry)
        for n, (deps, clearance, carry) in sorted(h.grows.items())
        if tmap.has_node(n) and tmap.node(n).degree == len(carry)
    ]


def ports_in_place(
    low: tuple[float, ...],
    px: int,
    high: tuple[float, ...],
    py: int,
    tol_rad: float,
    bound_rad: float,
    low_ends: tuple[bool | None, ...] = (),
    high_ends: tuple[bool | None, ...] = (),
) -> tuple[float, dict[int, int]] | None:
    """How a reading ``low`` of a place, one departure short of the reading ``high``, lies
    in it, port ``px`` being port ``py``: (the turn from ``low`` to ``high``, low port ->
    high port); None if it does not. Both in order of bearing, so the ports keep their
    cyclic order with one of ``high``'s left out. Every port agrees in angle under one turn
    within ``bound_rad``, but that one of ``low``'s may be two of ``high``'s read as one,
    lying between the one it goes to and the one left out, beside it (the 0.29 m pair by
    fig14's east table: its south and east edges read as one, between the two). The fit
    with every port agreeing wins, then the one that agrees best.

    ``low_ends``, ``high_ends``: per port, whether its edge leads to a boundary point (None
    if untraced, as ``Signature.to_boundary``). A port goes to no port whose edge leads to
    the other kind of node. Angles alone may pick the wrong one of the two edges read as
    one: at fig14's junction by the lab's east wall (seed 5 at drift paper), a reading of 31
    degrees, the edge east to a meet point, was nearer the dead end at 61 than the meet
    point at 7, and the merge then found the place read twice "looks otherwise"."""
    dl, dh = len(low), len(high)
    if dh != dl + 1 or not (0 <= px < dl and 0 <= py < dh):
        return None
    best: tuple[tuple[bool, float], float, dict[int, int]] | None = None
    for out in range(dh):
        if out == py:
            continue
        rest = [i for i in ((py + s) % dh for s in range(dh)) if i != out]
        to = {(px + s) % dl: rest[s] for s in range(dl)}
        if low_ends and high_ends and any(
            low_ends[p] is not None and high_ends[i] is not None and low_ends[p] != high_ends[i]
            for p, i in to.items()
        ):
            continue
        beside = [p for p, i in to.items() if (i - out) % dh in (1, dh - 1)]
        for merged in (None, *beside):
            diffs = [high[to[p]] - low[p] for p in to if p != merged]
            turn = math.atan2(sum(map(math.sin, diffs)), sum(map(math.cos, diffs)))
            if angdiff(turn, 0.0) > bound_rad:
                continue
            errs = [angdiff(high[to[p]] - turn, low[p]) for p in to if p != merged]
            if max(errs) > tol_rad:
                continue
            if merged is not None:
                a, h1, h2 = low[merged] + turn, high[to[merged]], high[out]
                if angdiff(a, h1) + angdiff(a, h2) > angdiff(h1, h2) + MERGED_SLACK_RAD:
                    continue
            score = (merged is not None, sum(errs))
            if best is None or score < best[0]:
                best = (score, turn, to)
    return None if best is None else (best[1], best[2])

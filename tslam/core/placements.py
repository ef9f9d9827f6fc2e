"""Does the evidence for a localization hypothesis single out one place in the map?

A hypothesis says which old node each node of the fragment is; its confirmed predictions
are the fragment's edges that matched the map's, port for port and length for length. The
paper merges when one candidate remains. But a candidate set only holds what the robot
thought to test: a look-alike it never listed (its arrival edge was already explored, or the
signature was misread once) is not refuted, merely absent. So before a merge the fragment's
tested part, its nodes and the edges between them, is placed on the map afresh, everywhere
it fits: every other placement is a hypothesis the evidence does not exclude. In a building
whose wings mirror each other (fig15) that is the rule, and the ambiguity is then recorded
rather than guessed at.

With ``open_edges`` a fragment edge may also fall between two old departures that are both
unexplored: the map cannot say those two places are not joined so. In fig15 at drift
``severe`` (seed 2) the corner the robot had come back to was mapped with two of the
fragment's four edges untraced, while a rotated corner was mapped with all four, and dead
reckoning had turned by most of the rotation: the fragment fit the rotated one alone, and
was merged there (with ``cut_past`` on). Such a placement still needs one edge of the map
matched, or it says no more than that the nodes look alike (the hypothesis's crowd counts
those). The explorer holds a merge for such a placement but tests no hypothesis of it.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from dataclasses import dataclass, replace

from tslam.core.localize import Hypothesis, Tolerances
from tslam.core.signature import rotations
from tslam.core.topomap import TopoMap

Placement = dict[int, tuple[int, int]]  # fragment node -> (old node, rotation)
PairFit = Callable[[int, int, int], bool]  # (fragment node, old node, rotation) -> allowed


def other_placements(
    tmap: TopoMap,
    h: Hypothesis,
    tol: Tolerances,
    limit: int = 4,
    budget: int = 20000,
    fits: PairFit | None = None,
    open_edges: bool = False,
    dead_end_depth: float = 0.0,
) -> tuple[list[Placement], bool] | None:
    """Up to ``limit`` placements of ``h``'s fragment nodes other than ``h``'s own that fit
    the map as well, and whether ``h``'s own fits (an edge measured with a detour matched
    only as a lower bound, which is no proof); None if the search ran out of ``budget``
    steps. An edge into a dead end may be longer by ``dead_end_depth`` times as much as its
    boundary point was reached nearer the walls (``TopoMap.dead_end_gap``).
    """
    nodes = [x for x in h.mapping if tmap.has_node(x)]
    own = {x: h.mapping[x] for x in nodes}
    found = placements(tmap, nodes, tol, limit + 1, budget, fits, open_edges, dead_end_depth)
    if found is None:
        return None
    others = [p for p in found if p != own]
    return others[:limit], len(others) < len(found)


def placements(
    tmap: TopoMap,
    nodes: list[int],
    tol: Tolerances,
    limit: int,
    budget: int = 20000,
    fits: PairFit | None = None,
    open_edges: bool = False,
    dead_end_depth: float = 0.0,
) -> list[Placement] | None:
    """Up to ``limit`` placements of ``nodes`` and the edges between them on the map's
    other nodes, each pair passing ``fits`` if given; None if the search ran out of
    ``budget`` steps."""
    links = _links(tmap, nodes)
    order = _order(nodes, links)
    found: list[Placement] = []
    search = _Search(tmap, order, links, set(nodes), tol, fits, open_edges, budget, dead_end_depth)
    try:
        for placement in search.place({}):
            if open_edges and not search.matches(placement):
                continue
            found.append(placement)
            if len(found) >= limit:
                break
    except _BudgetError:
        return None
    return found


class _BudgetError(Exception):
    """The search for placements ran out of steps."""


def _links(tmap: TopoMap, nodes: list[int]) -> dict[int, list[tuple[int, int, int, float]]]:
    """Per node: (its port, the other node, that node's port, the edge's length) for the
    edges between the given nodes."""
    inside = set(nodes)
    out: dict[int, list[tuple[int, int, int, float]]] = {x: [] for x in nodes}
    for x in nodes:
        for p, e in enumerate(tmap.node(x).ports):
            if e is None:
                continue
            edge = tmap.edge(e)
            y, q = edge.other_end(x, p)
            if y in inside:
                out[x].append((p, y, q, edge.length_m))
    return out


def _order(nodes: list[int], links: dict[int, list[tuple[int, int, int, float]]]) -> list[int]:
    """Nodes in breadth-first order, so that each after a component's first is reached by
    an edge from one placed before it."""
    seen: list[int] = []
    for root in sorted(nodes):
        if root in seen:
            continue
        queue = [root]
        seen.append(root)
        while queue:
            x = queue.pop(0)
            for _, y, _, _ in links[x]:
                if y not in seen:
                    seen.append(y)
                    queue.append(y)
    return seen


@dataclass
class _Search:
    tmap: TopoMap
    order: list[int]
    links: dict[int, list[tuple[int, int, int, float]]]
    placed: set[int]
    tol: Tolerances
    fits: PairFit | None
    open_edges: bool
    budget: int  # steps left
    dead_end_depth: float = 0.0

    def place(self, done: Placement) -> Iterator[Placement]:
        if len(done) == len(self.order):
            yield dict(done)
            return
        x = self.order[len(done)]
        used = {c for c, _ in done.values()}
        for c, k in self._options(x, done):
            self.budget -= 1
            if self.budget < 0:
                raise _BudgetError
            if c in used or c in self.placed:
                continue
            if not self._edges_fit(x, c, k, done):
                continue
            if self.fits is not None and not self.fits(x, c, k):
                continue
            done[x] = (c, k)
            yield from self.place(done)
            del done[x]

    def matches(self, placement: Placement) -> bool:
        """Whether some edge between the placed nodes is an edge of the map, or there are
        no such edges to match."""
        tmap = self.tmap
        links = 0
        for x, (c, k) in placement.items():
            for p, _, _, _ in self.links[x]:
                links += 1
                if tmap.node(c).ports[(p + k) % tmap.node(c).degree] is not None:
                    return True
        return links == 0

    def _options(self, x: int, done: Placement) -> Iterator[tuple[int, int]]:
        """Where ``x`` could go: led by an edge from a placed neighbour, else anywhere it
        looks alike."""
        tmap, tol = self.tmap, self.tol
        sig = tmap.signature(x)
        for p, y, q, _ in self.links[x]:
            if y not in done:
                continue
            cy, ky = done[y]
            e = tmap.node(cy).ports[(q + ky) % tmap.node(cy).degree]
            if e is None:
                if not self.open_edges:
                    return
                break  # anywhere alike with that departure unexplored (_edges_fit)
            c, r = tmap.edge(e).other_end(cy, (q + ky) % tmap.node(cy).degree)
            k = (r - p) % tmap.node(c).degree
            if k in rotations(sig, tmap.signature(c), tol.clearance_m, tol.angle_rad):
                yield c, k
            return
        for other in tmap.nodes():
            if other.id in self.placed:
                continue
            for k in rotations(sig, tmap.signature(other.id), tol.clearance_m, tol.angle_rad):
                yield other.id, k

    def _edges_fit(self, x: int, c: int, k: int, done: Placement) -> bool:
        """Every edge from ``x`` to a placed node is an edge of the map, port for port, of
        a length within tolerance; with ``open_edges``, or joins two unexplored
        departures."""
        tmap = self.tmap
        deg = tmap.node(c).degree
        for p, y, q, length in self.links[x]:
            if y not in done and y != x:
                continue
            cy, ky = done[y] if y != x else (c, k)
            e = tmap.node(c).ports[(p + k) % deg]
            if e is None:
                far = tmap.node(cy).ports[(q + ky) % tmap.node(cy).degree]
                if self.open_edges and far is None and (cy, ky) != (c, k):
                    continue
                return False
            edge = tmap.edge(e)
            w, r = edge.other_end(c, (p + k) % deg)
            if w != cy or r != (q + ky) % tmap.node(cy).degree:
                return False
            tol = self.tol
            gap = tmap.dead_end_gap((x, y), (c, cy)) if self.dead_end_depth else 0.0
            if gap:
                tol = replace(tol, length_abs_m=tol.length_abs_m + self.dead_end_depth * gap)
            if not tol.length_ok(length, edge.length_m):
                return False
        return True

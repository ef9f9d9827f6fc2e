"""Where the robot stood at each node, to bound how far apart dead reckoning can put a place.

Each arrival at a node and each departure from one is a *stand*: the node, where dead
reckoning put the robot, and the encoder distance. Two stands in a row are a *hop*: the
odometry's own displacement between them, over its metres. A merged node is one place, so
the hops at its stands join, and the hops make a graph over the map's nodes.

Dead reckoning drifts with the metres driven. Between two nodes the robot last stood at long
apart in time, that is many metres; but the map may join them by a few hops driven at other
times (a corridor traced on the first lap, and again after the loop closed). The odometry's
displacement summed along the hops of the shortest such chain then bounds the distance
between the two places far tighter: a false merge that dead reckoning cannot refute over 67
metres driven (maze:5 seed 5 at drift ``severe``: six places ~10 m from their look-alikes,
0.13 of the metres) is 10 m apart over a chain of 25 m. But each hop's displacement is turned
by the heading error of its time, and hops driven hundreds of metres apart differ by tens of
degrees: the sum does not allow for that yet, so the explorer leaves it off
(``ExplorerParams.drift_chain``).
"""

from __future__ import annotations

import heapq
import math
from collections.abc import Iterable

Hop = tuple[int, float, float, float]  # the other node, metres, displacement x, y
Pair = tuple[int, int]


class Stands:
    """The robot's stands at nodes, in order; nodes renamed by merges resolve to the merged."""

    def __init__(self) -> None:
        self._log: list[tuple[int, float, float, float]] = []
        self._renamed: dict[int, int] = {}

    def add(self, node: int, x_m: float, y_m: float, distance_m: float) -> None:
        """The robot stands at ``node``; dead reckoning puts it at ``(x, y)`` (odometry
        frame), after ``distance_m`` of encoder travel."""
        self._log.append((node, x_m, y_m, distance_m))

    def rename(self, old: int, new: int) -> None:
        """``old`` was merged into ``new``: stands at either are at one place."""
        if old != new:
            self._renamed[old] = new

    def node(self, n: int) -> int:
        while n in self._renamed:
            n = self._renamed[n]
        return n

    def chains(self, pairs: Iterable[Pair]) -> dict[Pair, tuple[float, float]]:
        """For each pair of nodes ``(a, b)`` the hops join: the distance dead reckoning's
        displacement adds up to along the chain of fewest metres from ``a`` to ``b``, and
        those metres. Pairs that no hops join, or that are one node already, are left out."""
        pairs = list(pairs)
        graph = self._graph()
        wanted: dict[int, set[int]] = {}
        for a, b in pairs:
            wanted.setdefault(self.node(a), set()).add(self.node(b))
        out: dict[Pair, tuple[float, float]] = {}
        for a, targets in wanted.items():
            found = _shortest(graph, a, targets - {a})
            for b, (metres, dx, dy) in found.items():
                out[(a, b)] = (math.hypot(dx, dy), metres)
        return {(a, b): out[key] for a, b in pairs if (key := (self.node(a), self.node(b))) in out}

    def _graph(self) -> dict[int, list[Hop]]:
        graph: dict[int, list[Hop]] = {}
        for (a, xa, ya, da), (b, xb, yb, db) in zip(self._log, self._log[1:], strict=False):
            a, b = self.node(a), self.node(b)
            if a == b:
                continue
            metres, dx, dy = abs(db - da), xb - xa, yb - ya
            graph.setdefault(a, []).append((b, metres, dx, dy))
            graph.setdefault(b, []).append((a, metres, -dx, -dy))
        return graph


def _shortest(
    graph: dict[int, list[Hop]], start: int, targets: set[int]
) -> dict[int, tuple[float, float, float]]:
    """Dijkstra by metres from ``start``: each target reached, with the metres and the
    displacement summed along the way."""
    best: dict[int, tuple[float, float, float]] = {start: (0.0, 0.0, 0.0)}
    done: set[int] = set()
    queue = [(0.0, start)]
    left = set(targets)
    while queue and left:
        metres, n = heapq.heappop(queue)
        if n in done:
            continue
        done.add(n)
        left.discard(n)
        _, dx, dy = best[n]
        for m, hop_m, hx, hy in graph.get(n, ()):
            total = metres + hop_m
            if m not in best or total < best[m][0]:
                best[m] = (total, dx + hx, dy + hy)
                heapq.heappush(queue, (total, m))
    return {t: best[t] for t in targets if t in done}

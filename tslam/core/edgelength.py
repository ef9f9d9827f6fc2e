"""The length of the GVG edge being traced, from the encoders and the sonar together.

The robot's own path is longer than the edge: the trace law weaves about it (the ring gives
each wall's bearing only to a transducer spacing, so the tangent swings), homing onto what
turns out not to be a meet point is a detour, and so is re-accessing the edge after losing
it. The encoders' distance over such a path overstated fig12's edges by 4-6 % at the median
and by up to 19 % (`tslam trace --world fig12 --edges 12`, seeds 1-3, drift `paper`).

While tracing, the sonar says where the edge is: ``G = d1 - d2`` and its gradient give the
step that would take the robot onto it (``-pinv(grad G) G``, ``laws.step_onto_edge``, the
term the trace law steers by). The dead-reckoned position plus that step is a point of the
edge. Those points are averaged over ``spacing_m`` of travel (each step is as noisy as two
sonar distances) and joined by straight chords, from the node the edge left to where it
ends. Dead reckoning is trusted over one edge only, as the paper trusts translation.

Off the edge (departing, homing, re-accessing, backing off a contact) no point is taken, so
a detour is bridged by a chord between the edge points either side of it. (An average that
spans a detour is kept: closing it there was tried and measured worse, since the brief
stretches traced while the robot flaps between access and trace near a junction are often
along another pair of walls.)

A point the chain goes out to and comes back from is not the edge's, and is dropped: points
traced past a meet point before homing back onto it (fig1 seed 1: 0.3 m past the junction and
back, 2.55 m measured for an edge of 2.03), or along another pair of walls in a doorway half
way (fig1 seed 3: 9.45 m for 8.20).

A way that comes back to the node it left, having gone out along another edge first (a
departure not held, the robot back through the junction and off along the next), begins
there again: the chain out and back is several points long, and no single one is a spike
(fig13 seed 1 at drift none, 746-807 s: 0.8 m out west and back, 3.25 m measured for an
edge of 2.25, and the place the robot had come back to could never be merged).
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, field

Point = tuple[float, float]


@dataclass
class EdgeOdometer:
    """``start`` at a node, ``on_edge`` while tracing, ``length_to`` at the next node."""

    spacing_m: float = 0.5
    max_step_m: float = 0.3  # a longer step is not onto this edge (another pair of walls)
    # A point of the chain whose two chords are this many times as long as the chord that
    # skips it is a spike, not the edge's (a right-angle bend, legs alike, is 1.41 times).
    detour_ratio: float = 1.5
    # Chain points this close to either end are dropped: about a node the two nearest walls
    # are often another edge's pair, and a point there is the junction's, a few centimetres
    # behind the start or past the end (fig13 seed 7: 1.24 m for 1.14). Over issue 3's 60
    # traces the edge-length target held in 41 at 0, 46 at 0.1, 49 at 0.15 and 51 at 0.25
    # or 0.3; an edge shorter than twice this is measured end to end, which a close pair's
    # straight edge is.
    end_clear_m: float = 0.25
    # Back this close to where the edge began, having been ``out_m`` but never ``far_m``
    # from it, the edge begins again (0: never). Further out, the way may be an edge that
    # comes round to its own node (round a pillar), whose end is no way back.
    back_m: float = 0.0
    out_m: float = 0.5
    far_m: float = 1.5
    _far: float = field(default=0.0, init=False)  # the furthest the way has been from its node
    _chain: list[Point] = field(default_factory=list, init=False)
    # The pending average: sum of x, sum of y, count; and the encoder distance it began at.
    _sum: list[float] = field(default_factory=lambda: [0.0, 0.0, 0.0], init=False)
    _sum_from_m: float = field(default=0.0, init=False)

    def start(self, x_m: float, y_m: float) -> None:
        """A node at ``(x, y)`` (odometry frame): an edge begins here."""
        self._chain = [(x_m, y_m)]
        self._sum = [0.0, 0.0, 0.0]
        self._far = 0.0

    def on_edge(self, x_m: float, y_m: float, distance_m: float, step: Point) -> None:
        """Tracing at ``(x, y)``; ``step`` (odometry frame) takes the robot onto the edge;
        ``distance_m`` is the encoder's total travel."""
        if not self._chain:
            return
        if self.back_m > 0.0:
            off = math.dist((x_m, y_m), self._chain[0])
            self._far = max(self._far, off)
            if off < self.back_m and self.out_m <= self._far < self.far_m:
                self.start(*self._chain[0])
        if math.hypot(*step) > self.max_step_m:
            return
        acc = self._sum
        if acc[2] == 0.0:
            self._sum_from_m = distance_m
        acc[0] += x_m + step[0]
        acc[1] += y_m + step[1]
        acc[2] += 1.0
        if distance_m - self._sum_from_m >= self.spacing_m:
            self._close()

    def length_to(self, x_m: float, y_m: float) -> float | None:
        """The edge's length if it ends at ``(x, y)`` now; None if no edge was started."""
        if not self._chain:
            return None
        pending = self._pending()
        chain = [*self._chain, *([pending] if pending is not None else []), (x_m, y_m)]
        first, last, clear = chain[0], chain[-1], self.end_clear_m
        inner = [
            q for q in chain[1:-1] if math.dist(q, first) >= clear and math.dist(q, last) >= clear
        ]
        chain = _without_spikes([first, *inner, last], self.detour_ratio)
        return float(sum(math.dist(a, b) for a, b in itertools.pairwise(chain)))

    @property
    def origin(self) -> Point | None:
        """Where the edge began (the node ``start`` was given), if it did."""
        return self._chain[0] if self._chain else None

    def _pending(self) -> Point | None:
        acc = self._sum
        return (acc[0] / acc[2], acc[1] / acc[2]) if acc[2] > 0.0 else None

    def _close(self) -> None:
        p = self._pending()
        if p is not None and self._chain:
            self._chain.append(p)
        self._sum = [0.0, 0.0, 0.0]


def _without_spikes(chain: list[Point], ratio: float) -> list[Point]:
    """``chain`` without the points that it goes out to and comes back from: while some
    point's two chords are ``ratio`` times as long as the one chord that would skip it, the
    worst such point is dropped. The two ends stay."""
    pts = list(chain)
    while len(pts) > 2:
        worst, k_worst = ratio, 0
        for k in range(1, len(pts) - 1):
            skip = math.dist(pts[k - 1], pts[k + 1])
            via = math.dist(pts[k - 1], pts[k]) + math.dist(pts[k], pts[k + 1])
            if via > worst * max(skip, 1e-9):
                worst, k_worst = via / max(skip, 1e-9), k
        if not k_worst:
            return pts
        del pts[k_worst]
    return pts

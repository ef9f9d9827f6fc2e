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
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

Point = tuple[float, float]


@dataclass
class EdgeOdometer:
    """``start`` at a node, ``on_edge`` while tracing, ``length_to`` at the next node."""

    spacing_m: float = 0.5
    max_step_m: float = 0.3  # a longer step is not onto this edge (another pair of walls)
    _last: Point | None = field(default=None, init=False)  # the last point of the chain
    _length: float = field(default=0.0, init=False)  # of the chain so far
    # The pending average: sum of x, sum of y, count; and the encoder distance it began at.
    _sum: list[float] = field(default_factory=lambda: [0.0, 0.0, 0.0], init=False)
    _sum_from_m: float = field(default=0.0, init=False)

    def start(self, x_m: float, y_m: float) -> None:
        """A node at ``(x, y)`` (odometry frame): an edge begins here."""
        self._last = (x_m, y_m)
        self._length = 0.0
        self._sum = [0.0, 0.0, 0.0]

    def on_edge(self, x_m: float, y_m: float, distance_m: float, step: Point) -> None:
        """Tracing at ``(x, y)``; ``step`` (odometry frame) takes the robot onto the edge;
        ``distance_m`` is the encoder's total travel."""
        if self._last is None or math.hypot(*step) > self.max_step_m:
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
        if self._last is None:
            return None
        pending = self._pending()
        if pending is None:
            return self._length + math.dist(self._last, (x_m, y_m))
        return self._length + math.dist(self._last, pending) + math.dist(pending, (x_m, y_m))

    def _pending(self) -> Point | None:
        acc = self._sum
        return (acc[0] / acc[2], acc[1] / acc[2]) if acc[2] > 0.0 else None

    def _close(self) -> None:
        p = self._pending()
        if p is not None and self._last is not None:
            self._length += math.dist(self._last, p)
            self._last = p
        self._sum = [0.0, 0.0, 0.0]

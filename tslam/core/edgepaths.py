"""Where the robot went along the edges it traced last, by dead reckoning.

Dead reckoning is good over metres and poor over a building, so only the last few edges are
kept, each with the encoder distance at which it ended: a caller asks for a path only while
the robot has travelled little since. What it is for: a meet point found partway along an
edge just traced (the first pass went by it without homing) is placed on that pass, and the
pass says which of its departures leads on to the far end.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

from hal.types import Odometry


@dataclass(frozen=True)
class EdgePath:
    start: int  # the node it was traced from
    points: tuple[tuple[float, float, float], ...]  # (metres from the start, x, y), odometry frame
    end_distance_m: float  # the encoder distance when it ended

    @property
    def length_m(self) -> float:
        return self.points[-1][0] if self.points else 0.0

    def nearest(self, x: float, y: float) -> tuple[float, float]:
        """(metres from the start, distance) of the recorded point nearest ``(x, y)``."""
        best = min(self.points, key=lambda p: (p[1] - x) ** 2 + (p[2] - y) ** 2)
        return best[0], math.hypot(best[1] - x, best[2] - y)

    def measured_as(self, length_m: float) -> EdgePath:
        """The path with its distances in the measure of ``length_m``, the traversal's edge
        length: the encoders count the weave about the edge, which the edge's own length
        leaves out (edgelength.py), so the two differ by some per cent. A ratio beyond that
        means the record is not of this traversal; the path is then returned as it is, for
        the caller's length check to refuse."""
        own = self.length_m
        if own <= 0.0 or not 0.75 <= length_m / own <= 1.05:
            return self
        k = length_m / own
        return EdgePath(
            self.start, tuple((s * k, x, y) for s, x, y in self.points), self.end_distance_m
        )

    def at(self, s: float) -> tuple[float, float]:
        """The point ``s`` metres from the start (clamped to the path)."""
        pts = self.points
        if s <= pts[0][0]:
            return pts[0][1], pts[0][2]
        for (s0, x0, y0), (s1, x1, y1) in itertools.pairwise(pts):
            if s <= s1:
                t = 0.0 if s1 == s0 else (s - s0) / (s1 - s0)
                return x0 + t * (x1 - x0), y0 + t * (y1 - y0)
        return pts[-1][1], pts[-1][2]


class EdgePaths:
    """Records the edge being traced; keeps the last ``keep`` finished ones by edge id."""

    def __init__(self, keep: int = 16, spacing_m: float = 0.05) -> None:
        self.keep = keep
        self.spacing_m = spacing_m
        self._live: list[tuple[float, float, float]] = []  # (encoder distance, x, y)
        self._done: dict[int, EdgePath] = {}

    def restart(self) -> None:
        self._live = []

    def add(self, odo: Odometry) -> None:
        if not self._live or odo.distance_m - self._live[-1][0] >= self.spacing_m:
            self._live.append((odo.distance_m, odo.x_m, odo.y_m))

    def live(self, start: int, distance_m: float) -> EdgePath | None:
        """The edge being recorded, so far, traced from node ``start``."""
        if len(self._live) < 2:
            return None
        d0 = self._live[0][0]
        return EdgePath(start, tuple((d - d0, x, y) for d, x, y in self._live), distance_m)

    def finish(self, edge: int, start: int, distance_m: float) -> None:
        """The edge being recorded was ``edge``, traced from node ``start``."""
        path = self.live(start, distance_m)
        if path is not None:
            self._done.pop(edge, None)
            self._done[edge] = path
            while len(self._done) > self.keep:
                self._done.pop(next(iter(self._done)))
        self._live = []

    def get(self, edge: int) -> EdgePath | None:
        return self._done.get(edge)

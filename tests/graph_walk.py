"""A true GVG as a graph, walked by the explorer's decisions without a simulator.

Each ``choose`` of the explorer picks a departure index; the walker follows that edge of the
true graph and reports the next node exactly as the tracer would (departure bearings in the
drifting odometry frame, the arrival index, the edge's encoder length), so localization and
the arbiter can be tested on graphs built to be hard, fast and deterministically.
"""

from __future__ import annotations

import math
import random
from collections.abc import Callable, Collection
from dataclasses import dataclass, field

from tslam.core.explorer import Explorer
from tslam.core.tracer import BoundaryReached, MeetPointReached

TAU = 2 * math.pi


@dataclass
class TrueGraph:
    """Nodes: id -> (kind, clearance, absolute departure bearings ascending, x, y).
    Edges: (node, port) -> (node, port, length)."""

    nodes: dict[str, tuple[str, float, tuple[float, ...], float, float]] = field(
        default_factory=dict
    )
    ends: dict[tuple[str, int], tuple[str, int, float]] = field(default_factory=dict)
    _done: set[tuple[int, int]] = field(default_factory=set)

    def meet(self, name: str, x: float, y: float, bearings_deg: list[float], clr: float = 1.0):
        deps = tuple(sorted(math.radians(b) % TAU for b in bearings_deg))
        self.nodes[name] = ("meet", clr, deps, x, y)

    def boundary(self, name: str, x: float, y: float) -> None:
        self.nodes[name] = ("boundary", 0.4, (0.0,), x, y)

    def port(self, name: str, bearing_deg: float) -> int:
        deps = self.nodes[name][2]
        b = math.radians(bearing_deg) % TAU
        return min(range(len(deps)), key=lambda i: abs((deps[i] - b + math.pi) % TAU - math.pi))

    def edge(self, a: str, bearing_a: float, b: str, bearing_b: float, length: float) -> None:
        pa = self.port(a, bearing_a)
        pb = 0 if self.nodes[b][0] == "boundary" else self.port(b, bearing_b)
        self.ends[(a, pa)] = (b, pb, length)
        self.ends[(b, pb)] = (a, pa, length)


def walk(
    graph: TrueGraph,
    explorer: Explorer,
    start: str,
    arrival_port: int | None = None,
    max_arrivals: int = 200,
    drift_deg_per_edge: float = 3.0,
    noise: float = 0.0,
    seed: int = 1,
    misread: Callable[[str, int | None, int], list[float] | None] | None = None,
    lost_at: Collection[int] = (),
    passed: Callable[[str, int, int], int | None] | None = None,
    read_distance: bool = False,
) -> list[str]:
    """Run the explorer over ``graph`` from ``start``; returns the true nodes visited.

    ``lost_at``: the arrivals (counted from 0) that come with no arrival index, as when the
    tracer lost its edge on the way: the explorer is then off the graph.

    ``misread(node, true arrival port, visits so far)`` may return other bearings (degrees,
    true frame) for the tracer to report at that arrival: a junction read with an edge more
    or fewer. Departure indices then map to the true ports by nearest bearing.

    ``passed(node, true arrival port, passes so far)`` may return the port by which the robot
    goes on through that meet point without homing there (a junction the ring does not
    resolve); the tracer then reports the node beyond, with both edges' length.

    ``read_distance``: each new meet node is stamped with the distance travelled so far, as
    the robot's encoder stamps it, so the explorer's heading check at a merge (turned no
    further than drift over that distance allows) is in play. Off, it is never applied."""
    rng = random.Random(seed)
    heading_err = 0.0
    at, came_by, length = start, arrival_port, None
    visited: list[str] = []
    gone_through: list[str] = []
    where = [graph.nodes[at][3], graph.nodes[at][4]]  # what the truth callback reports
    explorer.truth = lambda: (where[0], where[1])
    travelled = 0.0
    if read_distance:
        add_meet = explorer._add_meet

        def stamped(ev: MeetPointReached) -> int:
            node = add_meet(ev)
            explorer.born[node] = travelled
            return node

        explorer._add_meet = stamped  # type: ignore[method-assign]
    for _ in range(max_arrivals):
        _, clr, deps, x, y = graph.nodes[at]
        where[:] = [x, y]
        read = misread(at, came_by, visited.count(at)) if misread else None
        visited.append(at)
        shown = deps if read is None else tuple(math.radians(b) % TAU for b in read)
        seen = tuple((d - heading_err) % TAU for d in shown)
        order = sorted(range(len(seen)), key=lambda i: seen[i])
        obs = tuple(seen[i] for i in order)
        # The true port each reported departure leads along (nearest bearing).
        true_port = [_nearest(deps, shown[i]) for i in order]
        arr = None
        if came_by is not None and len(visited) - 1 not in lost_at:
            arr = min(range(len(obs)), key=lambda i: _angdiff(shown[order[i]], deps[came_by]))
        ev = MeetPointReached(
            0.0, x, y, clr + rng.uniform(-noise, noise), len(obs), obs, arr,
            tuple((d - obs[arr or 0]) % TAU for d in obs), length,
        )  # fmt: skip
        explorer._now += 1.0
        travelled += length or 0.0
        k = explorer._choose(ev)
        if explorer.held:  # done, or standing at the node it was sent to
            break
        port = true_port[k]
        nxt, nport, length = graph.ends[(at, port)]
        length *= 1.0 + rng.uniform(-noise, noise)
        while passed is not None and graph.nodes[nxt][0] == "meet":
            out = passed(nxt, nport, gone_through.count(nxt))
            if out is None:
                break
            gone_through.append(nxt)
            nxt, nport, more = graph.ends[(nxt, out)]
            length += more * (1.0 + rng.uniform(-noise, noise))
        heading_err += math.radians(drift_deg_per_edge)
        if graph.nodes[nxt][0] == "boundary":
            bx, by = graph.nodes[nxt][3], graph.nodes[nxt][4]
            where[:] = [bx, by]
            explorer._on_boundary(BoundaryReached(0.0, bx, by, 0.4, length))
            travelled += length
            visited.append(nxt)
            came_by = port  # straight back
        else:
            at, came_by = nxt, nport
    return visited


def from_ground_truth(gvg: object) -> TrueGraph:
    """The true graph of a world's ground-truth GVG (meet and boundary points only)."""
    g = TrueGraph()
    keep = {n.id: n for n in gvg.nodes if n.kind in ("meet", "boundary")}  # type: ignore[attr-defined]
    for n in keep.values():
        if n.kind == "meet":
            bearings = [math.degrees(a) for a in n.departure_angles]
            g.meet(str(n.id), n.x, n.y, bearings, n.clearance_m)
        else:
            g.boundary(str(n.id), n.x, n.y)
    for n in keep.values():
        for a, e in zip(n.departure_angles, n.departure_edges, strict=True):
            edge = next(x for x in gvg.edges if x.id == e)  # type: ignore[attr-defined]
            other = edge.v if edge.u == n.id else edge.u
            if other not in keep or (n.id, e) in g._done:
                continue
            o = keep[other]
            ob = next(b for b, oe in zip(o.departure_angles, o.departure_edges, strict=True)
                      if oe == e and (other != n.id or b != a))
            g.edge(str(n.id), math.degrees(a), str(other), math.degrees(ob), edge.length_m)
            g._done |= {(n.id, e), (other, e)}
    return g


def _angdiff(a: float, b: float) -> float:
    return abs((a - b + math.pi) % TAU - math.pi)


def _nearest(deps: tuple[float, ...], bearing: float) -> int:
    return min(range(len(deps)), key=lambda i: _angdiff(deps[i], bearing))


def straight_on(graph: TrueGraph, node: str, came_by: int) -> int:
    """The port of ``node`` most nearly opposite the one the robot came in by."""
    deps = graph.nodes[node][2]
    ahead = deps[came_by] + math.pi
    return min(
        (p for p in range(len(deps)) if p != came_by), key=lambda p: _angdiff(deps[p], ahead)
    )


def passed_once(graph: TrueGraph, junction: str) -> Callable[[str, int, int], int | None]:
    """A ``passed`` callback for ``walk``: the robot goes straight on through ``junction``
    without homing the first time it comes there, and homes there after."""

    def passed(node: str, came_by: int, before: int) -> int | None:
        return straight_on(graph, node, came_by) if node == junction and before == 0 else None

    return passed

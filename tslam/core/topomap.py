"""The topological map: meet points, boundary points and the GVG edges between them.

It holds what the paper says the robot stores (section V-C) and nothing it would have to
trust dead reckoning for: each node's clearance and the departure angles of its edges, which
edge leaves by which departure ("port"), and every encoder length measured along each edge.
A node's dead-reckoned pose is kept for drawing and for the naive baseline of section IV
only; no operation here reads it. Departures are in the odometry frame of the first visit,
counter-clockwise and ascending, so a port index is stable for the life of the node, unless
the node is read again as the close pair's place it is part of (``reread``).

Two meet points may be joined by two edges, and an edge may come back to the node it left,
so the graph underneath is a networkx ``MultiGraph`` keyed by edge id. Nodes and edges are
frozen records; every change goes through a method that keeps ports and edges in agreement
and appends a numbered ``Change`` to a log, so a link can publish the map incrementally.

Identifying two visits as one place (``merge``) follows the topology through: if the edge
leaving port 2 of the revisit is port 1's edge of the old node, both edges are one edge and
their far ends one node, and so on until nothing new follows, or a contradiction is found and
nothing changes. That is how "5 is 1" in the paper's Fig. 12 also settles "6 is 2, 7 is 3".
"""

from __future__ import annotations

import itertools
import math
import statistics
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import Any, NamedTuple

import networkx as nx

from tslam.core.frames import TAU
from tslam.core.signature import Signature, rotations

KINDS = ("meet", "boundary")
FORMAT = "tslam-map"
FORMAT_VERSION = 1


class MapError(ValueError):
    """An operation the map refuses because the map would contradict itself."""


class EdgeConflictError(MapError):
    """A merge would make two edges of different lengths one."""

    def __init__(self, message: str, edges: tuple[int, int]) -> None:
        super().__init__(message)
        self.edges = edges


class DegreeConflictError(MapError):
    """A merge would make two meet nodes one whose degrees differ by one, each reached by an
    edge the merge makes one: ``ends`` are the two (node, port) of that edge's ends."""

    def __init__(self, message: str, ends: tuple[tuple[int, int], tuple[int, int]]) -> None:
        super().__init__(message)
        self.ends = ends


class MapFormatError(ValueError):
    """A serialised map that cannot be read; the message names the field, node or edge."""


@dataclass(frozen=True)
class Node:
    id: int
    kind: str  # "meet" or "boundary"
    clearance_m: float
    departures_rad: tuple[float, ...]  # odometry frame at first visit, ascending, in [0, 2pi]
    ports: tuple[int | None, ...]  # per departure: the edge leaving by it, None if unexplored
    pose: tuple[float, float]  # dead-reckoned at first visit: drawing and baseline only
    truth: tuple[float, float] | None = None  # simulation only, for scoring
    ambiguous_with: frozenset[int] = frozenset()

    @property
    def degree(self) -> int:
        return len(self.departures_rad)


@dataclass(frozen=True)
class Edge:
    id: int
    u: int
    port_u: int
    v: int
    port_v: int
    lengths_m: tuple[float, ...]  # every encoder measurement, in the order taken

    @property
    def length_m(self) -> float:
        """The median: one traversal spoiled by a detour or wheel slip does not move it."""
        return statistics.median(self.lengths_m)

    def other_end(self, node: int, port: int) -> tuple[int, int]:
        """The (node, port) at the far end when leaving ``node`` by ``port``."""
        if (node, port) == (self.u, self.port_u):
            return self.v, self.port_v
        if (node, port) == (self.v, self.port_v):
            return self.u, self.port_u
        raise MapError(f"edge {self.id} does not leave node {node} by port {port}")


class Link(NamedTuple):
    """One explored departure of a node: leave by ``port`` along ``edge``, arrive at
    ``node`` by its ``node_port``."""

    port: int
    edge: int
    node: int
    node_port: int


class Step(NamedTuple):
    """One edge of a planned path: the tracer's next departure and where it should end."""

    node: int
    port: int
    edge: int
    next_node: int
    arrival_port: int


class Frontier(NamedTuple):
    node: int
    port: int  # the unexplored departure to take there
    path: list[Step]
    length_m: float


@dataclass(frozen=True)
class Change:
    """One numbered map change; ``data`` is plain JSON (ids, numbers, node/edge dicts)."""

    seq: int
    # node_added, edge_added, measurement, merge, ambiguity, node_removed, edge_split,
    # edge_removed
    op: str
    data: dict[str, Any]


@dataclass(frozen=True)
class Likeness:
    """How alike two nodes or two edges must be for a merge to make them one. A merge
    identifies more than the pair it was asked for: every edge the two share a port with is
    one edge, so its far ends are one node, and so on. Kind and degree alone let a port read
    wrongly once carry a proven merge on to a place that only has the same degree (fig13
    seed 5 with the tracer's centred_meet: two junctions merged onto places 3.5 m and 6.6 m
    from them)."""

    clearance_m: float
    angle_rad: float
    length_abs_m: float
    length_rel: float
    # Two edges into a dead end may differ by this many times as much as their boundary
    # points' clearances do: where the boundary rule stops the robot is no stable feature
    # (``dead_end_gap``).
    dead_end_depth: float = 0.0

    def lengths_agree(self, a: float, b: float, dead_end_gap_m: float = 0.0) -> bool:
        slack = self.length_abs_m + self.length_rel * max(a, b)
        return abs(a - b) <= slack + self.dead_end_depth * dead_end_gap_m


@dataclass(frozen=True)
class MergePlan:
    """What a merge would do. ``nodes``: dropped node -> (kept node, shift of its ports);
    ``edges``: dropped edge -> the edge it turned out to be."""

    keep: int
    drop: int
    rotation: int
    nodes: dict[int, tuple[int, int]] = field(default_factory=dict)
    edges: dict[int, int] = field(default_factory=dict)


def _number(
    v: object, where: str, err: type[ValueError] = MapError, lo: float = -math.inf
) -> float:
    if isinstance(v, bool) or not isinstance(v, int | float):
        raise err(f"{where} must be a number, not {_tname(v)}")
    if not math.isfinite(v) or v < lo:
        raise err(f"{where} must be a finite number >= {lo}, not {v!r}")
    return float(v)


def _integer(v: object, where: str, err: type[ValueError] = MapError) -> int:
    if isinstance(v, bool) or not isinstance(v, int):
        raise err(f"{where} must be an integer, not {_tname(v)}")
    return v


def _departures(values: Iterable[object], where: str, err: type[ValueError]) -> tuple[float, ...]:
    # TAU itself is allowed: the tracer's ``x % TAU`` returns it for x a hair below zero.
    deps = tuple(_number(a, f"{where}[{i}]", err) for i, a in enumerate(values))
    if not deps:
        raise err(f"{where} must list at least one departure")
    for i, a in enumerate(deps):
        if not 0.0 <= a <= TAU:
            raise err(f"{where}[{i}] = {a!r} is outside [0, 2pi]")
        if i and a <= deps[i - 1]:
            raise err(f"{where} must be strictly ascending (counter-clockwise)")
    return deps


def _pose(v: object, where: str, err: type[ValueError]) -> tuple[float, float]:
    if not isinstance(v, list | tuple) or len(v) != 2:
        raise err(f"{where} must be a pair [x, y]")
    return _number(v[0], f"{where}[0]", err), _number(v[1], f"{where}[1]", err)


def node_to_dict(n: Node) -> dict[str, Any]:
    d: dict[str, Any] = {
        "id": n.id,
        "kind": n.kind,
        "clearance_m": n.clearance_m,
        "degree": n.degree,
        "departures_rad": list(n.departures_rad),
        "ports": list(n.ports),
        "pose": list(n.pose),
        "ambiguous_with": sorted(n.ambiguous_with),
    }
    if n.truth is not None:
        d["truth"] = {"x": n.truth[0], "y": n.truth[1]}
    return d


def edge_to_dict(e: Edge) -> dict[str, Any]:
    return {
        "id": e.id,
        "u": e.u,
        "port_u": e.port_u,
        "v": e.v,
        "port_v": e.port_v,
        "length_m": e.length_m,
        "lengths_m": list(e.lengths_m),
    }


class TopoMap:
    """The map. Ids start at 1, like the paper's labels, and are never reused."""

    def __init__(self) -> None:
        self._nodes: dict[int, Node] = {}
        self._edges: dict[int, Edge] = {}
        self._graph = nx.MultiGraph()
        self._next_node = 1
        self._next_edge = 1
        self._log: list[Change] = []

    # -- reading ----------------------------------------------------------------------------

    @property
    def version(self) -> int:
        """Sequence number of the last change (0 for a fresh or freshly loaded map)."""
        return self._log[-1].seq if self._log else 0

    @property
    def changes(self) -> tuple[Change, ...]:
        return tuple(self._log)

    def changes_since(self, seq: int) -> list[Change]:
        """The changes a subscriber that has seen up to ``seq`` is missing."""
        return [c for c in self._log if c.seq > seq]

    @property
    def graph(self) -> nx.MultiGraph:
        """A read-only view: nodes by id, edges keyed by edge id with ``length_m``."""
        return self._graph.copy(as_view=True)

    def node(self, n: int) -> Node:
        try:
            return self._nodes[n]
        except (KeyError, TypeError):
            raise MapError(f"no node {n!r} in the map") from None

    def edge(self, e: int) -> Edge:
        try:
            return self._edges[e]
        except (KeyError, TypeError):
            raise MapError(f"no edge {e!r} in the map") from None

    def has_node(self, n: int) -> bool:
        return n in self._nodes

    def has_edge(self, e: int) -> bool:
        return e in self._edges

    def nodes(self) -> list[Node]:
        return [self._nodes[k] for k in sorted(self._nodes)]

    def edges(self) -> list[Edge]:
        return [self._edges[k] for k in sorted(self._edges)]

    def neighbours(self, n: int) -> list[Link]:
        """Explored departures of ``n`` in port order (a self-loop shows up twice)."""
        node = self.node(n)
        return [
            Link(p, e, *self._edges[e].other_end(n, p))
            for p, e in enumerate(node.ports)
            if e is not None
        ]

    def unexplored(self) -> list[tuple[int, int]]:
        """Every (node, port) no edge has left by yet; exploration ends when it is empty."""
        return [(n.id, p) for n in self.nodes() for p, e in enumerate(n.ports) if e is None]

    # -- building ---------------------------------------------------------------------------

    def add_meet(
        self,
        clearance_m: float,
        departures_rad: Iterable[float],
        pose: tuple[float, float],
        truth: tuple[float, float] | None = None,
    ) -> int:
        """A newly homed meet point (``MeetPointReached``): every port starts unexplored."""
        deps = _departures(departures_rad, "departures_rad", MapError)
        return self._add_node("meet", clearance_m, deps, pose, truth)

    def add_boundary(
        self,
        clearance_m: float,
        pose: tuple[float, float],
        departure_rad: float = 0.0,
        truth: tuple[float, float] | None = None,
    ) -> int:
        """A boundary point: one departure, back the way the robot came."""
        dep = _number(departure_rad, "departure_rad") % TAU
        return self._add_node("boundary", clearance_m, (dep,), pose, truth)

    def _add_node(
        self,
        kind: str,
        clearance_m: float,
        deps: tuple[float, ...],
        pose: tuple[float, float],
        truth: tuple[float, float] | None,
    ) -> int:
        node = Node(
            self._next_node,
            kind,
            _number(clearance_m, "clearance_m", lo=0.0),
            deps,
            (None,) * len(deps),
            _pose(pose, "pose", MapError),
            None if truth is None else _pose(truth, "truth", MapError),
        )
        self._next_node += 1
        self._nodes[node.id] = node
        self._graph.add_node(node.id)
        self._record("node_added", {"node": node_to_dict(node)})
        return node.id

    def connect(self, u: int, port_u: int, v: int, port_v: int, length_m: float) -> int:
        """Record a traversed edge between two free ports; returns the new edge id."""
        length = _number(length_m, "length_m", lo=0.0)
        for n, p in ((u, port_u), (v, port_v)):
            node = self.node(n)
            if isinstance(p, bool) or not isinstance(p, int) or not 0 <= p < node.degree:
                raise MapError(f"node {n} has no port {p!r} (degree {node.degree})")
            if node.ports[p] is not None:
                raise MapError(f"port {p} of node {n} is already taken by edge {node.ports[p]}")
        if u == v and port_u == port_v:
            raise MapError(f"an edge cannot leave and return to node {u} by the same port {port_u}")
        edge = Edge(self._next_edge, u, port_u, v, port_v, (length,))
        self._next_edge += 1
        self._put_edge(edge)
        self._record("edge_added", {"edge": edge_to_dict(edge)})
        return edge.id

    def split_edge(
        self, e: int, node: int, port: int, mid: int, near_port: int, far_port: int, near_m: float
    ) -> tuple[int, int]:
        """Edge ``e``, left from ``node`` by ``port``, runs through the meet point ``mid``
        (one its first tracing passed without homing): it becomes two edges, ``node`` to
        ``mid``'s ``near_port`` (``near_m`` long, as measured) and ``mid``'s ``far_port`` to
        the far end (the rest of ``e``'s length). Returns the two new edge ids."""
        edge = self.edge(e)
        far, far_q = edge.other_end(node, port)
        m = self.node(mid)
        if mid in (node, far) or near_port == far_port:
            raise MapError(f"node {mid} cannot split edge {e} by ports {near_port}, {far_port}")
        for p in (near_port, far_port):
            if isinstance(p, bool) or not isinstance(p, int) or not 0 <= p < m.degree:
                raise MapError(f"node {mid} has no port {p!r} (degree {m.degree})")
            if m.ports[p] is not None:
                raise MapError(f"port {p} of node {mid} is already taken by edge {m.ports[p]}")
        near = _number(near_m, "near_m", lo=0.0)
        if near >= edge.length_m:
            raise MapError(f"edge {e} is {edge.length_m:.2f} m long: cannot split it at {near} m")
        self._drop_edge(e)
        a = Edge(self._next_edge, node, port, mid, near_port, (near,))
        b = Edge(self._next_edge + 1, mid, far_port, far, far_q, (edge.length_m - near,))
        self._next_edge += 2
        for x in (a, b):
            self._put_edge(x)
        into = [edge_to_dict(a), edge_to_dict(b)]
        self._record("edge_split", {"edge": e, "node": mid, "into": into})
        return a.id, b.id

    def remove_edge(self, e: int) -> None:
        """Forget an edge found to have gone past a junction without homing there: its
        two ports become unexplored again."""
        self.edge(e)
        self._drop_edge(e)
        self._record("edge_removed", {"edge": e})

    def add_measurement(self, edge: int, length_m: float) -> None:
        """Another encoder length for a retraced edge; the estimate is their median."""
        e = self.edge(edge)
        length = _number(length_m, "length_m", lo=0.0)
        e = replace(e, lengths_m=(*e.lengths_m, length))
        self._edges[edge] = e
        self._graph.edges[e.u, e.v, e.id]["length_m"] = e.length_m
        self._record("measurement", {"edge": edge, "length_m": length})

    def set_ambiguous(self, n: int, others: Iterable[int]) -> None:
        """Replace the set of nodes ``n`` cannot be told apart from (section VII-A); the
        relation is symmetric, so the other nodes' sets are updated too."""
        node = self.node(n)
        new = frozenset(self.node(o).id for o in others) - {n}
        touched = {n} | new | node.ambiguous_with
        for o in new ^ node.ambiguous_with:
            other = self._nodes[o]
            amb = other.ambiguous_with | {n} if o in new else other.ambiguous_with - {n}
            self._nodes[o] = replace(other, ambiguous_with=amb)
        self._nodes[n] = replace(node, ambiguous_with=new)
        sets = [[t, sorted(self._nodes[t].ambiguous_with)] for t in sorted(touched)]
        self._record("ambiguity", {"sets": sets})

    def reread(
        self, n: int, departures_rad: Sequence[float], clearance_m: float, carry: Mapping[int, int]
    ) -> None:
        """Meet node ``n`` read again as the place it is part of (section VII-B's close meet
        points): its departures become ``departures_rad``; the edge on each explored port
        ``p`` moves to port ``carry[p]``. Unexplored ports not carried are dropped: they led
        inside the place."""
        node = self.node(n)
        if node.kind != "meet":
            raise MapError(f"node {n} is a {node.kind} node: only a meet node is read again")
        deps = _departures(departures_rad, "departures_rad", MapError)
        clearance = _number(clearance_m, "clearance_m", lo=0.0)
        ports: list[int | None] = [None] * len(deps)
        for p, e in enumerate(node.ports):
            if e is None:
                continue
            q = carry.get(p)
            if q is None or not 0 <= q < len(deps) or ports[q] is not None:
                raise MapError(f"node {n}: port {p}'s edge {e} has no port of its own")
            ports[q] = e
        for e in set(node.ports) - {None}:
            old = self._edges[e]  # a loop edge has both its ends here
            self._edges[e] = replace(
                old,
                port_u=carry[old.port_u] if old.u == n else old.port_u,
                port_v=carry[old.port_v] if old.v == n else old.port_v,
            )
        self._nodes[n] = replace(
            node, departures_rad=deps, ports=tuple(ports), clearance_m=clearance
        )
        self._record(
            "node_reread",
            {
                "node": node_to_dict(self._nodes[n]),
                "edges": [edge_to_dict(self._edges[e]) for e in sorted(set(ports) - {None})],
            },
        )

    def remove_node(self, n: int) -> None:
        """Forget a node and its edges; their far ends become unexplored again."""
        self.node(n)
        gone = sorted({lk.edge for lk in self.neighbours(n)})
        for e in gone:
            self._drop_edge(e)
        del self._nodes[n]
        self._graph.remove_node(n)
        for o, other in list(self._nodes.items()):
            if n in other.ambiguous_with:
                self._nodes[o] = replace(other, ambiguous_with=other.ambiguous_with - {n})
        self._record("node_removed", {"node": n, "edges": gone})

    # -- merging ----------------------------------------------------------------------------

    def plan_merge(
        self, keep: int, drop: int, rotation: int, alike: Likeness | None = None
    ) -> MergePlan:
        """Work out, without changing anything, what ``merge`` would do; raise ``MapError``
        if the identification contradicts the map: a kind or degree that differs, and with
        ``alike`` a signature or an edge's length that does. Cheap enough to test a
        hypothesis."""
        a = self.node(keep)
        self.node(drop)
        if keep == drop:
            raise MapError(f"cannot merge node {keep} with itself")
        alias: dict[int, tuple[int, int]] = {}  # n -> (parent, k): n's port j = parent's j + k

        def find(n: int) -> tuple[int, int]:
            shift = 0
            while n in alias:
                n, k = alias[n]
                shift += k
            return n, shift % self._nodes[n].degree

        def identify(x: int, y: int, k: int, ports: tuple[int, int] | None = None) -> bool:
            """Port j of y is port j + k of x (``ports``: the port of each an edge made one
            arrives by). True if this taught something new."""
            rx, sx = find(x)
            ry, sy = find(y)
            nx_, ny_ = self._nodes[rx], self._nodes[ry]
            if (nx_.kind, nx_.degree) != (ny_.kind, ny_.degree):
                why = (
                    f"merging {drop} into {keep} would make {ny_.kind} {y} (degree {ny_.degree})"
                    f" the same place as {nx_.kind} {x} (degree {nx_.degree})"
                )
                one_more = abs(nx_.degree - ny_.degree) == 1
                if ports is not None and nx_.kind == ny_.kind == "meet" and one_more:
                    ends = (
                        (rx, (ports[0] + sx) % nx_.degree),
                        (ry, (ports[1] + sy) % ny_.degree),
                    )
                    raise DegreeConflictError(why, ends)
                raise MapError(why)
            rel = (k + sx - sy) % nx_.degree
            if alike is not None and rx != ry:
                fits = rotations(
                    self.signature(ry), self.signature(rx), alike.clearance_m, alike.angle_rad
                )
                if rel not in fits:
                    raise MapError(
                        f"merging {drop} into {keep} would make node {ry} the same place as "
                        f"node {rx}, which looks otherwise"
                    )
            if rx == ry:
                if rel:
                    raise MapError(
                        f"merging {drop} into {keep} would identify node {y} with node {x}"
                        " under two different rotations"
                    )
                return False
            # keep survives; otherwise the older node does.
            if ry == keep or (rx != keep and ry < rx):
                alias[rx] = (ry, -rel % nx_.degree)
            else:
                alias[ry] = (rx, rel)
            return True

        if isinstance(rotation, bool) or not isinstance(rotation, int):
            raise MapError(f"rotation must be an integer shift of ports, not {rotation!r}")
        identify(keep, drop, rotation)
        while True:
            slots = self._slots(find)
            learnt = False
            for users in slots.values():
                e1, end1 = users[0]
                o1, q1 = self._edges[e1].other_end(*self._end(e1, end1))
                for e2, end2 in users[1:]:
                    if e2 == e1:
                        raise MapError(
                            f"merging {drop} into {keep} would make edge {e1} leave and"
                            " return by the same port"
                        )
                    # e2 is e1, so their far ends are one (node, port) too.
                    l1, l2 = self._edges[e1].length_m, self._edges[e2].length_m
                    o2, q2 = self._edges[e2].other_end(*self._end(e2, end2))
                    gap = self.dead_end_gap(
                        (self._end(e1, end1)[0], o1), (self._end(e2, end2)[0], o2)
                    )
                    if alike is not None and not alike.lengths_agree(l1, l2, gap):
                        raise EdgeConflictError(
                            f"merging {drop} into {keep} would make edge {e2} ({l2:.2f} m) "
                            f"edge {e1} ({l1:.2f} m)",
                            (e1, e2),
                        )
                    learnt |= identify(o1, o2, q1 - q2, (q1, q2))
            if not learnt:
                break
        # Edges sharing a slot are one edge; the oldest id of each group survives.
        parent: dict[int, int] = {}

        def root(e: int) -> int:
            while e in parent:
                e = parent[e]
            return e

        for users in slots.values():
            ids = sorted({root(e) for e, _ in users})
            for e in ids[1:]:
                parent[e] = ids[0]
        edges = {e: root(e) for e in sorted(parent)}
        return MergePlan(keep, drop, rotation % a.degree, {n: find(n) for n in alias}, edges)

    def dead_end_gap(self, a: tuple[int, int], b: tuple[int, int]) -> float:
        """How much nearer the walls one of two edges' dead ends was reached than the other:
        ``a`` and ``b`` are the two edges' ends taken as the same places, in the same order.
        The boundary rule stops the robot where the gap pinches, and the nearer the walls
        it stops, the deeper in (fig14 seed 1: one dead end mapped 0.36 m and 0.67 m from
        its junction, at clearances 0.44 m and 0.29 m)."""
        gap = 0.0
        for x, y in zip(a, b, strict=True):
            nx_, ny_ = self._nodes[x], self._nodes[y]
            if nx_.kind == ny_.kind == "boundary":
                gap += abs(nx_.clearance_m - ny_.clearance_m)
        return gap

    def _end(self, e: int, end: int) -> tuple[int, int]:
        edge = self._edges[e]
        return (edge.u, edge.port_u) if end == 0 else (edge.v, edge.port_v)

    def _slots(self, find: Any) -> dict[tuple[int, int], list[tuple[int, int]]]:
        """(surviving node, port) -> the edge ends that would land there; only crowded ones."""
        slots: dict[tuple[int, int], list[tuple[int, int]]] = {}
        for e in sorted(self._edges):
            for end in (0, 1):
                n, p = self._end(e, end)
                r, s = find(n)
                slots.setdefault((r, (p + s) % self._nodes[r].degree), []).append((e, end))
        return {k: v for k, v in slots.items() if len(v) > 1}

    def merge(
        self, keep: int, drop: int, rotation: int, alike: Likeness | None = None
    ) -> MergePlan:
        """Two nodes are one place: port j of ``drop`` is port ``(j + rotation) % degree`` of
        ``keep`` (a shift from ``signature_rotations(drop, keep, ...)``). Everything the
        topology then forces merges too; all or nothing. ``keep`` keeps its pose and frame."""
        plan = self.plan_merge(keep, drop, rotation, alike)

        def mapped(n: int, p: int) -> tuple[int, int]:
            r, s = plan.nodes.get(n, (n, 0))
            return r, (p + s) % self._nodes[r].degree

        old_nodes, old_edges = dict(self._nodes), dict(self._edges)
        edges: dict[int, Edge] = {}
        for e in sorted(self._edges):
            edge = self._edges[e]
            if e in plan.edges:
                target = edges[plan.edges[e]]
                edges[target.id] = replace(target, lengths_m=target.lengths_m + edge.lengths_m)
            else:
                (u, pu), (v, pv) = mapped(edge.u, edge.port_u), mapped(edge.v, edge.port_v)
                edges[e] = replace(edge, u=u, port_u=pu, v=v, port_v=pv)
        nodes: dict[int, Node] = {}
        for n, node in self._nodes.items():
            if n not in plan.nodes:
                nodes[n] = replace(node, ports=(None,) * node.degree, ambiguous_with=frozenset())
        for n, node in self._nodes.items():
            root = plan.nodes.get(n, (n, 0))[0]
            amb = {plan.nodes.get(x, (x, 0))[0] for x in node.ambiguous_with} - {root}
            nodes[root] = replace(nodes[root], ambiguous_with=nodes[root].ambiguous_with | amb)
        for edge in edges.values():
            for n, p in ((edge.u, edge.port_u), (edge.v, edge.port_v)):
                ports = list(nodes[n].ports)
                assert ports[p] is None, "plan_merge left two edges on one port"
                ports[p] = edge.id
                nodes[n] = replace(nodes[n], ports=tuple(ports))
        self._nodes, self._edges = nodes, edges
        self._rebuild_graph()
        self._record(
            "merge",
            {
                "keep": keep,
                "drop": drop,
                "rotation": plan.rotation,
                "nodes": [[d, r, s] for d, (r, s) in sorted(plan.nodes.items())],
                "edges": [[d, k] for d, k in sorted(plan.edges.items())],
                "updated_nodes": [
                    node_to_dict(v) for k, v in sorted(nodes.items()) if old_nodes[k] != v
                ],
                "updated_edges": [
                    edge_to_dict(v) for k, v in sorted(edges.items()) if old_edges[k] != v
                ],
            },
        )
        return plan

    # -- signatures and planning ------------------------------------------------------------

    def signature(self, n: int) -> Signature:
        node = self.node(n)
        to_boundary = tuple(
            None if e is None else self._nodes[self._edges[e].other_end(n, p)[0]].kind == "boundary"
            for p, e in enumerate(node.ports)
        )
        return Signature(node.kind, node.clearance_m, node.departures_rad, to_boundary)

    def signature_rotations(
        self, a: int, b: int, clearance_tol_m: float, angle_tol_rad: float
    ) -> list[int]:
        """Shifts k under which node ``a`` looks like node ``b`` (port j of a = port j + k
        of b); empty means certainly different places. See ``tslam.core.signature``."""
        return rotations(self.signature(a), self.signature(b), clearance_tol_m, angle_tol_rad)

    def shortest_path(
        self, src: int, dst: int, extra_m: Mapping[int, float] | None = None
    ) -> list[Step]:
        """The graph path by median edge length: what the robot retraces to get somewhere
        (section V-B), as departures to take, never as x, y waypoints. ``extra_m``: edge id
        -> metres added to that edge's length (an edge the robot could not follow)."""
        self.node(src), self.node(dst)
        if src == dst:
            return []
        try:
            nodes = nx.dijkstra_path(self._graph, src, dst, weight=_weighted(extra_m))
        except nx.NetworkXNoPath:
            raise MapError(f"no path from node {src} to node {dst}") from None
        return self._steps(nodes, extra_m)

    def distances(self, src: int, extra_m: Mapping[int, float] | None = None) -> dict[int, float]:
        """Graph distance from ``src`` to every node it reaches (``shortest_path``'s measure)."""
        self.node(src)
        return nx.single_source_dijkstra_path_length(self._graph, src, weight=_weighted(extra_m))

    def nearest_unexplored(self, src: int) -> Frontier | None:
        """The closest node with an unexplored departure (section III-D), or None when
        exploration is complete. Ties go to the lower node id, then the lower port."""
        self.node(src)
        dist, paths = nx.single_source_dijkstra(self._graph, src, weight=_weight)
        best = min(((d, n) for n, d in dist.items() if None in self._nodes[n].ports), default=None)
        if best is None:
            return None
        d, n = best
        return Frontier(n, self._nodes[n].ports.index(None), self._steps(paths[n]), d)

    def _steps(self, nodes: list[int], extra_m: Mapping[int, float] | None = None) -> list[Step]:
        out, extra = [], extra_m or {}
        for a, b in itertools.pairwise(nodes):
            e = min(
                self._graph[a][b], key=lambda k: (self._edges[k].length_m + extra.get(k, 0.0), k)
            )
            edge = self._edges[e]
            pa, pb = (edge.port_u, edge.port_v) if edge.u == a else (edge.port_v, edge.port_u)
            out.append(Step(a, pa, e, b, pb))
        return out

    # -- derived views ----------------------------------------------------------------------

    def copy(self) -> TopoMap:
        """An independent map with the same content, ids and change log."""
        out = self._restore(dict(self._nodes), dict(self._edges))
        out._log = list(self._log)
        out._next_node, out._next_edge = self._next_node, self._next_edge
        return out

    def reduced(self) -> TopoMap:
        """The reduced GVG of section VII-B, as a new map with a fresh change log.

        Weak meet points sit beside shallow indents, so they have a boundary point next to
        them. For every meet point with a boundary neighbour: the boundary spurs go; if two
        departures remain, the point is just a point on one longer edge, so it goes and its
        two edges are joined (lengths summed; an unexplored side leaves the far end
        unexplored); with three or more it is still a real junction and stays, with fewer
        ports; with one it is now a dead end and stays. A point alone on a loop stays too.
        """
        out = self.copy()
        out._log = []
        weak = [
            n.id for n in self.nodes() if n.kind == "meet" and any(self.signature(n.id).to_boundary)
        ]
        for w in weak:
            spurs = [lk for lk in out.neighbours(w) if out._nodes[lk.node].kind == "boundary"]
            for lk in spurs:
                del out._edges[lk.edge]
                del out._nodes[lk.node]
            out._drop_ports(w, {lk.port for lk in spurs})
        for w in weak:
            node = out._nodes[w]
            if node.degree == 0:
                del out._nodes[w]
            elif node.degree == 2 and (node.ports[0] is None or node.ports[0] != node.ports[1]):
                out._splice(w)
        for n, node in list(out._nodes.items()):
            out._nodes[n] = replace(node, ambiguous_with=node.ambiguous_with & out._nodes.keys())
        out._rebuild_graph()
        return out

    def _drop_ports(self, n: int, drop: set[int]) -> None:
        node = self._nodes[n]
        keep = [p for p in range(node.degree) if p not in drop]
        new_index = {p: i for i, p in enumerate(keep)}
        for e in {node.ports[p] for p in keep} - {None}:
            edge = self._edges[e]
            self._edges[e] = replace(
                edge,
                port_u=new_index[edge.port_u] if edge.u == n else edge.port_u,
                port_v=new_index[edge.port_v] if edge.v == n else edge.port_v,
            )
        self._nodes[n] = replace(
            node,
            departures_rad=tuple(node.departures_rad[p] for p in keep),
            ports=tuple(node.ports[p] for p in keep),
        )

    def _splice(self, w: int) -> None:
        node = self._nodes.pop(w)
        live = []
        for p, e in enumerate(node.ports):
            if e is not None:
                edge = self._edges.pop(e)
                live.append((edge, edge.other_end(w, p)))
        live.sort(key=lambda x: x[0].id)  # the joined edge runs like the older of the two
        if len(live) == 1:
            _, (o, q) = live[0]
            self._set_port(o, q, None)
        elif len(live) == 2:
            (e0, (a, pa)), (e1, (b, pb)) = live
            joined = Edge(min(e0.id, e1.id), a, pa, b, pb, (e0.length_m + e1.length_m,))
            self._edges[joined.id] = joined
            self._set_port(a, pa, joined.id)
            self._set_port(b, pb, joined.id)

    def _set_port(self, n: int, p: int, e: int | None) -> None:
        ports = list(self._nodes[n].ports)
        ports[p] = e
        self._nodes[n] = replace(self._nodes[n], ports=tuple(ports))

    # -- serialisation ----------------------------------------------------------------------

    def to_dict(self) -> dict[str, Any]:
        """Plain JSON data, nodes and edges by id (the change log is not part of it)."""
        return {
            "format": FORMAT,
            "version": FORMAT_VERSION,
            "nodes": [node_to_dict(n) for n in self.nodes()],
            "edges": [edge_to_dict(e) for e in self.edges()],
        }

    @classmethod
    def from_dict(cls, data: object) -> TopoMap:
        """Check everything, then build; any fault raises ``MapFormatError`` naming it."""
        nodes, edges = _read_map(data)
        return cls._restore(nodes, edges)

    @classmethod
    def _restore(cls, nodes: dict[int, Node], edges: dict[int, Edge]) -> TopoMap:
        out = cls()
        out._nodes, out._edges = nodes, edges
        out._next_node = max(nodes, default=0) + 1
        out._next_edge = max(edges, default=0) + 1
        out._rebuild_graph()
        return out

    # -- internals --------------------------------------------------------------------------

    def _put_edge(self, edge: Edge) -> None:
        self._edges[edge.id] = edge
        self._set_port(edge.u, edge.port_u, edge.id)
        self._set_port(edge.v, edge.port_v, edge.id)
        self._graph.add_edge(edge.u, edge.v, key=edge.id, length_m=edge.length_m)

    def _drop_edge(self, e: int) -> None:
        edge = self._edges.pop(e)
        for n, p in ((edge.u, edge.port_u), (edge.v, edge.port_v)):
            if n in self._nodes:
                self._set_port(n, p, None)
        self._graph.remove_edge(edge.u, edge.v, key=e)

    def _rebuild_graph(self) -> None:
        g = nx.MultiGraph()
        g.add_nodes_from(sorted(self._nodes))
        for e in self.edges():
            g.add_edge(e.u, e.v, key=e.id, length_m=e.length_m)
        self._graph = g

    def _record(self, op: str, data: Mapping[str, Any]) -> None:
        self._log.append(Change(self.version + 1, op, dict(data)))


def _weight(u: int, v: int, d: Mapping[int, Mapping[str, float]]) -> float:
    return min(attr["length_m"] for attr in d.values())


def _weighted(extra_m: Mapping[int, float] | None) -> Any:
    """Dijkstra's weight: ``_weight``, each edge id in ``extra_m`` that much longer."""
    if not extra_m:
        return _weight
    return lambda u, v, d: min(a["length_m"] + extra_m.get(k, 0.0) for k, a in d.items())


# -- reading a serialised map ---------------------------------------------------------------


def _tname(v: object) -> str:
    """JSON's names for types: the person reading the message wrote JSON, not Python."""
    if v is None:
        return "null"
    if isinstance(v, bool):
        return "boolean"
    if isinstance(v, int | float):
        return "number"
    return {dict: "object", list: "array", str: "string"}.get(type(v), type(v).__name__)


def _get(obj: Mapping[str, Any], key: str, where: str) -> Any:
    if key not in obj:
        raise MapFormatError(f"{where}: missing key {key!r}")
    return obj[key]


def _array(v: object, where: str) -> list[Any]:
    if not isinstance(v, list):
        raise MapFormatError(f"{where} must be an array, not {_tname(v)}")
    return v


def _object(v: object, where: str) -> Mapping[str, Any]:
    if not isinstance(v, dict):
        raise MapFormatError(f"{where} must be an object, not {_tname(v)}")
    return v


def _read_map(data: object) -> tuple[dict[int, Node], dict[int, Edge]]:
    err = MapFormatError
    top = _object(data, "the map")
    for key in ("format", "version", "nodes", "edges"):
        _get(top, key, "the map")
    if top["format"] != FORMAT:
        raise err(f"'format' is {top['format']!r}, expected {FORMAT!r}")
    if isinstance(top["version"], bool) or top["version"] != FORMAT_VERSION:
        raise err(f"unsupported 'version' {top['version']!r} (this reader knows {FORMAT_VERSION})")
    nodes: dict[int, Node] = {}
    for i, raw in enumerate(_array(top["nodes"], "'nodes'")):
        node = _read_node(raw, f"nodes[{i}]")
        if node.id in nodes:
            raise err(f"node {node.id}: duplicate id")
        nodes[node.id] = node
    edges: dict[int, Edge] = {}
    for i, raw in enumerate(_array(top["edges"], "'edges'")):
        edge = _read_edge(raw, f"edges[{i}]", nodes)
        if edge.id in edges:
            raise err(f"edge {edge.id}: duplicate id")
        edges[edge.id] = edge
    for e in edges.values():
        for n, p in ((e.u, e.port_u), (e.v, e.port_v)):
            if nodes[n].ports[p] != e.id:
                raise err(
                    f"edge {e.id}: leaves node {n} by port {p}, but that port of node {n}"
                    f" holds {nodes[n].ports[p]!r}"
                )
    for node in nodes.values():
        for p, e in enumerate(node.ports):
            if e is None:
                continue
            if e not in edges:
                raise err(f"node {node.id}: 'ports'[{p}] names edge {e}, which is not in the map")
            if (node.id, p) not in ((edges[e].u, edges[e].port_u), (edges[e].v, edges[e].port_v)):
                raise err(
                    f"node {node.id}: 'ports'[{p}] names edge {e}, which does not leave"
                    f" node {node.id} by port {p}"
                )
        for o in sorted(node.ambiguous_with):
            if o not in nodes or o == node.id:
                raise err(f"node {node.id}: 'ambiguous_with' names node {o}, not another node")
    return nodes, edges


def _read_node(raw: object, where: str) -> Node:
    err = MapFormatError
    obj = _object(raw, where)
    nid = _integer(_get(obj, "id", where), f"{where}: 'id'", err)
    where = f"node {nid}"
    kind = _get(obj, "kind", where)
    if kind not in KINDS:
        raise err(f"{where}: 'kind' must be 'meet' or 'boundary', not {kind!r}")
    clearance = _number(_get(obj, "clearance_m", where), f"{where}: 'clearance_m'", err, 0.0)
    degree = _integer(_get(obj, "degree", where), f"{where}: 'degree'", err)
    if degree < 1 or (kind == "boundary" and degree != 1):
        raise err(f"{where}: 'degree' {degree} is impossible for a {kind} point")
    key = f"{where}: 'departures_rad'"
    deps = _departures(_array(_get(obj, "departures_rad", where), key), key, err)
    if len(deps) != degree:
        raise err(f"{key} has {len(deps)} angles for degree {degree}")
    key = f"{where}: 'ports'"
    raw_ports = _array(_get(obj, "ports", where), key)
    if len(raw_ports) != degree:
        raise err(f"{key} has {len(raw_ports)} entries for degree {degree}")
    ports = tuple(
        None if p is None else _integer(p, f"{key}[{i}]", err) for i, p in enumerate(raw_ports)
    )
    pose = _pose(_get(obj, "pose", where), f"{where}: 'pose'", err)
    truth = None
    if obj.get("truth") is not None:
        t = _object(obj["truth"], f"{where}: 'truth'")
        tw = f"{where}: 'truth'"
        truth = (
            _number(_get(t, "x", tw), f"{tw}.x", err),
            _number(_get(t, "y", tw), f"{tw}.y", err),
        )
    key = f"{where}: 'ambiguous_with'"
    amb = frozenset(
        _integer(o, f"{key}[{i}]", err)
        for i, o in enumerate(_array(_get(obj, "ambiguous_with", where), key))
    )
    return Node(nid, kind, clearance, deps, ports, pose, truth, amb)


def _read_edge(raw: object, where: str, nodes: Mapping[int, Node]) -> Edge:
    err = MapFormatError
    obj = _object(raw, where)
    eid = _integer(_get(obj, "id", where), f"{where}: 'id'", err)
    where = f"edge {eid}"
    ends = []
    for nk, pk in (("u", "port_u"), ("v", "port_v")):
        n = _integer(_get(obj, nk, where), f"{where}: {nk!r}", err)
        if n not in nodes:
            raise err(f"{where}: {nk!r} is node {n}, which is not in the map")
        p = _integer(_get(obj, pk, where), f"{where}: {pk!r}", err)
        if not 0 <= p < nodes[n].degree:
            raise err(
                f"{where}: {pk!r} {p} is out of range for node {n} (degree {nodes[n].degree})"
            )
        ends.append((n, p))
    (u, pu), (v, pv) = ends
    if (u, pu) == (v, pv):
        raise err(f"{where}: leaves and returns to node {u} by the same port {pu}")
    key = f"{where}: 'lengths_m'"
    raw_lengths = _array(_get(obj, "lengths_m", where), key)
    if not raw_lengths:
        raise err(f"{key} is empty: an edge is only known by being measured")
    lengths = tuple(_number(x, f"{key}[{i}]", err, 0.0) for i, x in enumerate(raw_lengths))
    length = _number(_get(obj, "length_m", where), f"{where}: 'length_m'", err, 0.0)
    est = statistics.median(lengths)
    if abs(length - est) > 1e-9 * max(1.0, est):
        raise err(f"{where}: 'length_m' {length!r} is not the median of 'lengths_m' ({est!r})")
    return Edge(eid, u, pu, v, pv, lengths)

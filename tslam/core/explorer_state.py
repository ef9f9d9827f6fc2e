"""What the exploration arbiter knows between control cycles, and the small helpers every
part of it uses.

``Explorer`` is one state machine split by concern over a few modules (``arrival``,
``unhomed``, ``boundaries``, ``resolving``, ``heading_bounds``): each is a mixin over this
state, and their methods call one another through ``self``.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from typing import NamedTuple

from hal.interfaces import DriveLimits
from hal.types import Odometry
from tslam.core.edgepaths import EdgePaths
from tslam.core.explorer_params import ExplorerParams
from tslam.core.frames import TAU, angdiff
from tslam.core.localize import Hypotheses, Tolerances
from tslam.core.portmap import PortMap
from tslam.core.signature import Signature
from tslam.core.stands import Stands
from tslam.core.topomap import Likeness, MergePlan, Step, TopoMap
from tslam.core.tracer import BoundaryReached, MeetPointReached, Tracer, TracerParams
from tslam.core.zipmerge import Renames, merge_mapping

# Edges a hypothesis may say went past a junction (``Explorer._past_a_junction``).
MAX_CUTS = 2


class Past(NamedTuple):
    """A failed prediction explained by a junction passed without homing: ``beyond`` is
    the old node (and rotation) this traversal reached past the predicted one, or None if
    the map's edge went past the meet point just reached."""

    beyond: tuple[int, int] | None


@dataclass(frozen=True)
class MergeRecord:
    """Which node became which; the truths are copied for scoring only."""

    stamp_s: float
    pairs: tuple[tuple[int, int, tuple[float, float] | None, tuple[float, float] | None], ...]


@dataclass(frozen=True)
class Note:
    """Something worth telling the operator (progress lines, the link's event stream)."""

    stamp_s: float
    text: str


@dataclass(frozen=True)
class OwnReading:
    """What the robot read at a node taken as its predicted place (``PredictedPlace``), to
    give back if no hypothesis places it any more. ``index[p]``: the reading's departure for
    port ``p``."""

    departures_rad: tuple[float, ...]
    clearance_m: float
    index: tuple[int, ...]
    born_m: float | None  # encoder distance when read


class ExplorerState:
    """The arbiter's state; ``Explorer`` is this with its behaviour mixed in."""

    def __init__(
        self,
        limits: DriveLimits,
        tracer_params: TracerParams | None = None,
        params: ExplorerParams | None = None,
        truth: Callable[[], tuple[float, float]] | None = None,
        tmap: TopoMap | None = None,
    ) -> None:
        self.p = params or ExplorerParams()
        self.map = tmap or TopoMap()
        self._resuming = len(self.map.nodes()) > 0  # the first node is matched to the stored map
        self.tracer = Tracer(limits, tracer_params, choose=self._choose)
        self.hyps = Hypotheses()
        self._held: set[int] = set()  # hypotheses noted as waiting on untraced rivals
        self.truth = truth
        self.here: int | None = None  # the node the robot is at or last left
        self.leaving: tuple[int, int] | None = None  # (node, port) being traced
        self.detoured = False  # the tracer left the edge since, and did not rejoin it
        self.disturbed = False  # ... or left it and rejoined it: the length is only a bound
        self.wandered_m = 0.0  # ... the distance driven off the edge since (excursions)
        # Where an excursion off the edge began: x, y, encoder distance, the two flags above
        # as they stood then, and the tracer's tangent (the course it was on).
        self._detour_from: (
            tuple[float, float, float, bool, bool, tuple[float, float] | None] | None
        ) = None
        self.partial_m = 0.0  # length before a weak meet point passed through
        self._through: int | None = None  # ... and the departure that goes on through it
        # The departure being left by, when the robot homed on the way at its place's other
        # point: it leaves from there too, and the robot goes on by it (``_reread``).
        self._on_by: tuple[int, int] | None = None
        self._on_by_count: dict[tuple[int, int], int] = {}  # ... how often, by departure
        self.plan: list[Step] = []
        self.frozen: set[tuple[int, int]] = set()
        self.done = False
        self.goal: int | None = None  # a node an operator sent the robot to
        self.held = False  # standing at a meet point: done, or at its goal
        self._at: tuple[MeetPointReached, int, PortMap] | None = None  # where held
        self.merges: list[MergeRecord] = []
        self.verified: set[int] = set()  # edges gone back along once the map had no frontier
        # (node, port) the robot was sent back to a node by, shut in or to retry a departure
        # given up (shut_in.py).
        self.rechecked: set[tuple[int, int]] = set()
        self.notes: list[Note] = []
        self.bounces: dict[tuple[int, int], int] = {}
        self.failed: dict[int, int] = {}  # edge -> times set out along and lost (``_avoid``)
        self.went_along_another: set[tuple[int, int]] = set()  # ... not held so, once or more
        # Meet node -> how far apart two of its place's points were read (``_spans``).
        self.span: dict[int, float] = {}
        self._last_visit: tuple[int, tuple[float, ...], PortMap, float, float] | None = None
        # Meet node -> each port's bearing (odometry frame) when it was last read with every
        # edge apart; and the bearing to leave by in place of a reading's departure that two
        # ports share (``_departure_bearing``).
        self.port_bearings: dict[int, tuple[float, ...]] = {}
        self._depart_along: float | None = None
        # Meet nodes found by access into a room (``TracerParams.room_entry_m``): junctions
        # the ring does not show along the room's edges, so an edge to one is traced for its
        # length and the robot stands there (``Tracer.arrive_after``).
        self.blind: set[int] = set()
        self._arrive_after: tuple[float, tuple[float, ...]] | None = None
        self._straight_m = 0.0  # go on straight this far along the departure (_across_place)
        # (node, port, length out) of a dead end short along a mapped edge, the robot on its
        # way back to the node (``short_ends.py``); and the next departure records no pass.
        self._short_from: tuple[int, int, float] | None = None
        self._no_pass = False
        self._now = 0.0
        self._odo: Odometry | None = None
        self.paths = EdgePaths()
        self.born: dict[int, float] = {}  # meet node -> encoder distance its angles were read at
        # Node -> where dead reckoning put the robot when it last stood there, and the
        # encoder distance then (nodes of a stored map have none until visited).
        self.fixes: dict[int, tuple[float, float, float]] = {}
        # Every stand at a node, for the chained bound (``drift_chain``; kept only with it on:
        # a daemon's list would grow by every arrival for as long as it runs).
        self.stands = Stands()
        # Edge -> how far apart dead reckoning put its two ends, read one traversal apart.
        self.edge_gap: dict[int, float] = {}
        # Edges whose length is a walk's remainder (``_walked_to``): the measured way less the
        # mapped edges it went through, each off by up to a few decimetres.
        self.estimated: set[int] = set()
        # The node last recognised although read with another degree, and whether the edge
        # being traced left from it: its ports were matched by angle, so which departure
        # the robot took is a guess, and what it finds there tests no hypothesis.
        self._misread: int | None = None
        # New nodes read as the old place the hypotheses predicted (``_as_predicted``), with
        # the robot's own reading, given back if no hypothesis places them any more.
        self.own_reading: dict[int, OwnReading] = {}
        self.unsure_departure = False
        # Nodes whose look-alikes were tested and given up on: a copy of one of them may
        # stand in the map (``_lead_ins``).
        self.doubtful: set[int] = set()
        # The nodes of the map the robot was restarted with: the building it stopped in, so
        # a piece of them left out of reach is placed on less evidence (``_place_orphans``).
        self.stored: set[int] = {n.id for n in self.map.nodes()}

    def settled_map(self) -> TopoMap:
        """The map without the fragment whose hypotheses are open, nor a node left with no
        edge: what a restart may start from. The fragment's nodes are new places under one
        hypothesis and old ones under the rest; stored as new, they stood in the map beside
        the places they were (fig12 killed after three edges: the loop's first junction
        twice), every place the restarted robot found fitted both copies alike, and it mapped
        the room anew for hours."""
        out = self.map.copy()
        for n in sorted(self.unsettled()):
            out.remove_node(n)
        # A node with no edge can never be tested by a prediction: stored, it is a copy of a
        # place that no restart can name (fig1 killed on its second node, which looked like
        # its first: the first alone stayed beside its place for good).
        for node in out.nodes():
            if not out.neighbours(node.id):
                out.remove_node(node.id)
        return out

    def unsettled(self) -> frozenset[int]:
        """The nodes of the open question: ``settled_map`` leaves them out (and any node that
        leaves without an edge)."""
        if not self.hyps.live:
            return frozenset()
        return frozenset(n for n in self.hyps.fragment if self.map.has_node(n))

    def _one_place_clearances(self, a: float, b: float, tol: Tolerances) -> bool:
        """Whether clearances ``a`` and ``b`` may be one place's, read at two of its points:
        the nearest obstacle's distance changes by no more than the points lie apart."""
        return abs(a - b) <= tol.clearance_m + self.p.place_hop_m / 2

    def _distances(self, node: int) -> dict[int, float]:
        """Graph distance from ``node`` to every node it reaches, by the shortest edges, an
        edge the robot could not follow that much longer (``_avoid``)."""
        return self.map.distances(node, self._avoid())

    def _path(self, src: int, dst: int) -> list[Step]:
        """``TopoMap.shortest_path``, an edge the robot could not follow that much longer."""
        return self.map.shortest_path(src, dst, self._avoid())

    def _avoid(self) -> dict[int, float]:
        """Edge id -> metres added to its length for planning: ``failed_edge_m`` for each
        time the robot set out along it and was lost at its end."""
        m = self.p.failed_edge_m
        return {e: n * m for e, n in self.failed.items() if m > 0.0 and self.map.has_edge(e)}

    def _failed(self, node: int, port: int) -> None:
        """The robot set out from ``node`` by ``port`` along a mapped edge and did not arrive
        where the map said: one more failure of that edge."""
        if not self.map.has_node(node) or port >= len(self.map.node(node).ports):
            return
        e = self.map.node(node).ports[port]
        if e is not None:
            self.failed[e] = self.failed.get(e, 0) + 1

    def _given_up(self) -> list[tuple[int, int]]:
        """Unexplored departures given up: frozen after ``bounce_retries`` tries not held."""
        return [
            x
            for x in self.map.unexplored()
            if x in self.frozen and self.bounces.get(x, 0) > self.p.bounce_retries
        ]

    def unexplored(self) -> list[tuple[int, int]]:
        """Departures still to explore (those frozen by an ambiguity are left out)."""
        return [x for x in self.map.unexplored() if x not in self.frozen]

    def _seen(self, ev: MeetPointReached, a: int, came_from: int) -> Signature:
        tb: list[bool | None] = [None] * ev.degree
        tb[a] = self.map.node(came_from).kind == "boundary"
        return Signature("meet", ev.clearance_m, ev.departures_rad, tuple(tb))

    def _through_port(self, ev: MeetPointReached) -> int | None:
        a = ev.arrival_index
        if a is None:
            return None
        back = ev.departures_rad[a]
        ahead = (back + math.pi) % TAU
        best = min(range(ev.degree), key=lambda i: angdiff(ev.departures_rad[i], ahead))
        if best == a or angdiff(ev.departures_rad[best], ahead) > self.p.weak_through_rad:
            return None
        return best

    def _count_bounce(self, key: tuple[int, int], went_along_another: bool = False) -> None:
        """One more time departure ``key`` was not held; after the retries an unexplored one
        is given up. ``went_along_another``: the robot went out along another departure."""
        node, port = key
        if went_along_another:
            self.went_along_another.add(key)
        self.bounces[key] = self.bounces.get(key, 0) + 1
        if self.bounces[key] > self.p.bounce_retries and self.map.node(node).ports[port] is None:
            self.frozen.add(key)

    def _edge_left(self) -> int | None:
        """The map edge of the departure being traced, once it is known."""
        if self.leaving is None or not self.map.has_node(self.leaving[0]):
            return None
        ports = self.map.node(self.leaving[0]).ports
        return ports[self.leaving[1]] if self.leaving[1] < len(ports) else None

    def _in_hypotheses(self, node: int) -> bool:
        """Whether a live hypothesis places ``node`` or places a node on it: its ports are
        then what the hypothesis's rotation refers to."""
        return any(node in h.named for h in self.hyps.live)

    def _reread_node(
        self, node: int, departures_rad: Sequence[float], clearance_m: float, carry: dict[int, int]
    ) -> None:
        """Node ``node`` read again: its ports become ``departures_rad``, port ``p`` moving to
        ``carry[p]``; what is kept by port follows."""
        self.map.reread(node, departures_rad, clearance_m, carry)
        self.own_reading.pop(node, None)  # read anew: what it was read as before is moot
        # Each port on a departure of its own: where to leave by when a later reading sees
        # two as one (``_departure_bearing``; fig13 seed 9 left the 0.29 m pair's west point
        # for the east point's dead end by the departure it shares with the east edge).
        self.port_bearings[node] = tuple(departures_rad)
        kept = {(x, p) for x, p in self.frozen if x != node or p in carry}
        self.frozen = {(x, carry[p]) if x == node else (x, p) for x, p in kept}
        self.bounces = {k: v for k, v in self.bounces.items() if k[0] != node}
        self.went_along_another = {k for k in self.went_along_another if k[0] != node}

    def _port_bearings_read(
        self, node: int, deps: Sequence[float], pm: PortMap
    ) -> list[float] | None:
        """Each port's bearing in the reading ``deps`` of ``node``: its departure's, but for
        ports that share one (two edges seen as one departure between them) their bearing
        when last read apart, turned as the ports read apart both times have turned since.
        None if no port shares a departure, or the node was never read with all apart."""
        old = self.port_bearings.get(node)
        alone = alone_ports(pm.index)
        if old is None or len(old) != len(pm.index) or len(alone) in (0, len(pm.index)):
            return None
        turn = reading_turn(deps, pm.index, old, alone)
        return [deps[i] if p in alone else (old[p] + turn) % TAU for p, i in enumerate(pm.index)]

    def _add_meet(self, ev: MeetPointReached) -> int:
        truth = self.truth() if self.truth else None
        node = self.map.add_meet(ev.clearance_m, ev.departures_rad, (ev.x_m, ev.y_m), truth)
        if self._odo is not None:
            self.born[node] = self._odo.distance_m
        return node

    def _fix(self, node: int) -> None:
        if self._odo is not None:
            self.fixes[node] = (self._odo.x_m, self._odo.y_m, self._odo.distance_m)
            if self.p.drift_chain:
                self.stands.add(node, self._odo.x_m, self._odo.y_m, self._odo.distance_m)

    def _add_boundary(self, ev: BoundaryReached) -> int:
        truth = self.truth() if self.truth else None
        return self.map.add_boundary(ev.clearance_m, (ev.x_m, ev.y_m), truth=truth)

    def _likeness(self) -> Likeness:
        """What every pair a merge makes one must agree on: what a prediction is tested on."""
        t = self._tol()
        return Likeness(
            t.clearance_m, t.angle_rad, t.length_abs_m, t.length_rel, self.p.dead_end_depth
        )

    def _merge_recorded(
        self, mapping: dict[int, tuple[int, int]], alike: Likeness
    ) -> tuple[Renames, MergeRecord]:
        """Merge ``mapping`` into the map (``merge_mapping``; ``MapError`` as it raises) and
        record which node became which, with their truths for scoring."""
        truth = {n.id: n.truth for n in self.map.nodes()}  # dropped nodes vanish
        pairs: list[tuple[int, int, tuple[float, float] | None, tuple[float, float] | None]] = []

        def record(plan: MergePlan) -> None:
            pairs.extend((d, r, truth[d], truth[r]) for d, (r, _) in plan.nodes.items())

        renamed = merge_mapping(self.map, mapping, alike, record)
        self.blind |= {r for d, (r, _) in renamed.items() if d in self.blind}
        merged = MergeRecord(self._now, tuple(pairs))
        self.merges.append(merged)
        return renamed, merged

    def _tol(self, slack_m: float = 0.0, clearance_slack_m: float = 0.0) -> Tolerances:
        tol = self.p.tol
        if slack_m:
            tol = replace(tol, length_abs_m=tol.length_abs_m + slack_m)
        if clearance_slack_m:
            tol = replace(tol, clearance_m=tol.clearance_m + clearance_slack_m)
        if not self.disturbed:
            return tol
        return replace(tol, at_least=True, wandered_m=self.wandered_m)

    def _turn_bound(self, node: int) -> float:
        """How far dead reckoning's heading may have turned since ``node``'s angles were read
        (pi if they were not read by the robot's own encoders)."""
        born = self.born.get(node)
        if born is None or self._odo is None:
            return math.pi
        return self._heading_drift(abs(self._odo.distance_m - born))

    def _heading_drift(self, driven_m: float) -> float:
        """How far dead reckoning's heading may turn over ``driven_m`` metres."""
        return self.p.heading_base_rad + self.p.heading_drift_rad_per_m * driven_m

    def _edge_length(self, measured: float | None) -> float | None:
        """The edge's length from the encoders: the stretch before a weak meet point passed
        through, plus this stretch."""
        return None if measured is None else measured + self.partial_m

    def _size(self) -> str:
        return f"{len(self.map.nodes())} nodes, {len(self.map.edges())} edges"

    def _note(self, text: str) -> None:
        self.notes.append(Note(self._now, text))


def alone_ports(index: Sequence[int]) -> list[int]:
    """The ports of a port map (``PortMap.index``) on a departure of their own."""
    return [p for p, i in enumerate(index) if index.count(i) == 1]


def reading_turn(
    deps: Sequence[float], index: Sequence[int], ports_rad: Sequence[float], alone: list[int]
) -> float:
    """How far a reading's departures ``deps`` are turned from ports read at ``ports_rad``,
    port ``p`` being departure ``index[p]``: the mean over the ports in ``alone``."""
    return math.atan2(
        sum(math.sin(deps[index[p]] - ports_rad[p]) for p in alone),
        sum(math.cos(deps[index[p]] - ports_rad[p]) for p in alone),
    )


def nearest(bearing: float, deps: Sequence[float]) -> int:
    """The index of the departure in ``deps`` nearest ``bearing``."""
    return min(range(len(deps)), key=lambda p: angdiff(deps[p], bearing))

"""Two-dimensional localization (section V-C): is the meet point just reached new or old?

When the robot homes onto a meet point that looks like one already in the map, the map cannot
know yet whether it is back at that place or at a new one that looks the same. The new node goes
into the map (it *is* new under one hypothesis) and a ``Hypotheses`` set starts: each hypothesis
says which old node each new node of the *fragment* (the nodes found since) would be, and with
which rotation of its ports. Every edge the robot then traces from a fragment node is a test:
where a hypothesis maps that node to an old one whose corresponding departure is explored, it
predicts the edge's length and the node at its end, with the port the robot must arrive by. A
failed prediction kills the hypothesis; a met one counts as evidence.

Only the map's topology and edge lengths decide (the paper's stable features); dead reckoning is
never consulted. "All of them are new places" is always possible and never refuted by what the
robot sees, so a merge needs a single surviving hypothesis *and* confirmed predictions: the
paper's Fig. 12 merge came after two edges and three nodes matched.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from tslam.core.signature import Signature, rotations
from tslam.core.topomap import TopoMap


@dataclass(frozen=True)
class Tolerances:
    clearance_m: float = 0.15
    angle_rad: float = math.radians(25.0)
    # An edge's length is its own (edgelength.py), off by where homing stopped at each end
    # and by what a chord across a detour misses: 0.16-0.18 m at the 90th percentile on fig1
    # and fig13, 0.41-0.48 m at worst, against 0.25-0.31 m and 0.9-1.2 m when it was the
    # encoders' distance and these were 0.35 m and 12 %.
    length_abs_m: float = 0.25
    length_rel: float = 0.08  # ... and the tolerance grows with the edge
    # The robot left the edge and came back to it on the way: the wandering only adds to
    # the measured length, so a shorter measurement still refutes and a longer one does not.
    at_least: bool = False
    # ... but by no more than the distance it drove off the edge: back on its way from a dead
    # end, a robot that went through the junction unhomed measures two edges, not one plus
    # a few decimetres (fig12 seed 5: 6.5 m taken for 1.3 m, and the map was wrong for good).
    wandered_m: float = math.inf

    def length_slack(self, mapped: float) -> float:
        """How far a measured length may be off one of ``mapped`` metres."""
        return self.length_abs_m + self.length_rel * mapped

    def length_ok(self, measured: float | None, mapped: float) -> bool:
        if measured is None:
            return True
        slack = self.length_slack(mapped)
        if self.at_least:
            return mapped - slack <= measured <= mapped + slack + self.wandered_m
        return abs(measured - mapped) <= slack


@dataclass
class Hypothesis:
    """Fragment node -> (old node, rotation k): port j of the fragment node is port
    ``(j + k) % degree`` of the old node (the map's merge convention)."""

    mapping: dict[int, tuple[int, int]]
    confirmed: int = 0  # predicted meet points found where and as predicted
    dead_ends: int = 0  # predicted boundary points found: weak, every dead end looks alike
    silent_arrivals: int = 0  # arrivals in a row it made no prediction for
    lost_start: bool = False  # began at a node reached off the graph: no arrival port to test
    # Began at the first node after a restart from a stored map. The robot was in the mapped
    # building when it stopped, so the stored map is the prior: one surviving candidate that
    # nothing more can test is the paper's "one candidate remains", not a guess.
    resumed: bool = False
    # How many old nodes looked like the fragment's node when this hypothesis was made. Each
    # is a priori as likely as the next, so the odds for any one of them start at one in
    # ``crowd``; a confirmed prediction is worth about two bits (a length within a tolerance
    # some fraction of the edge, departure angles within 25 degrees), and a map crowded with
    # look-alikes (duplicates of a lab's junctions, fig15's aisles) needs that much more
    # evidence before one candidate is as good as proven.
    crowd: int = 1
    # Map edges this hypothesis says went past a junction without homing there: an old edge
    # its fragment found a meet point partway along, or a fragment edge that went past an
    # old node to the one beyond. They go from the map when the hypothesis is merged.
    cuts: set[int] = field(default_factory=set)
    # Nodes its merge reads again with an edge more, as the places they are (merge_grow.py):
    # node -> (departures, clearance, port p's edge moves to carry[p]). Worked out anew each
    # time the merge is tried.
    grows: dict[int, tuple[tuple[float, ...], float, dict[int, int]]] = field(default_factory=dict)

    @property
    def named(self) -> set[int]:
        """The nodes it places and the nodes it places them on."""
        return set(self.mapping) | {c for c, _ in self.mapping.values()}

    @property
    def tested(self) -> bool:
        return self.confirmed + self.dead_ends > 0

    def proven(self, merge_evidence: int, weigh_crowd: bool = True) -> bool:
        """Enough evidence to merge, if no other hypothesis is left. Dead ends count half,
        and a hypothesis that began off the graph needs one confirmation more: mirror-image
        corridors (fig16) agree on dead ends, and a node reached off the graph was matched on
        its signature alone. With ``weigh_crowd``, a crowd of look-alikes asks for more. Each
        edge it says went past a junction asks for one more: that is a slip it assumes."""
        need = merge_evidence + (1 if self.lost_start else 0) + len(self.cuts)
        if weigh_crowd:
            need += crowd_evidence(self.crowd)
        return self.confirmed >= 1 and self.confirmed + 0.5 * self.dead_ends >= need

    def image_port(self, tmap: TopoMap, node: int, port: int) -> tuple[int, int] | None:
        if node not in self.mapping:
            return None
        c, k = self.mapping[node]
        return c, (port + k) % tmap.node(c).degree


def crowd_evidence(crowd: int) -> int:
    """Confirmations needed beyond the usual to single out one of ``crowd`` look-alikes: one
    per two bits of prior odds, none for up to four."""
    return max(0, math.ceil(0.5 * math.log2(max(crowd, 1))) - 1)


@dataclass(frozen=True)
class Prediction:
    """What a hypothesis says the robot will find at the end of a departure."""

    node: int  # an old node
    arrival_port: int
    length_m: float
    kind: str
    edge: int | None = None  # the map edge it follows


@dataclass
class Hypotheses:
    fragment: set[int] = field(default_factory=set)
    live: list[Hypothesis] = field(default_factory=list)

    def __bool__(self) -> bool:
        return bool(self.live)

    def clear(self) -> None:
        self.fragment.clear()
        self.live.clear()

    def candidates_of(self, node: int) -> set[int]:
        return {h.mapping[node][0] for h in self.live if node in h.mapping}


def candidates(
    tmap: TopoMap,
    seen: Signature,
    tol: Tolerances,
    exclude: set[int],
    arrival_port: int | None,
) -> list[tuple[int, int]]:
    """Old nodes the node ``seen`` could be, with the rotation: signature matches and, if the
    robot came by a new edge, the corresponding departure of the old node must be unexplored
    too (a known edge would already have brought the robot there)."""
    out = []
    for other in tmap.nodes():
        if other.id in exclude or other.kind != seen.kind:
            continue
        sig = tmap.signature(other.id)
        for k in rotations(seen, sig, tol.clearance_m, tol.angle_rad):
            if (
                arrival_port is not None
                and other.ports[(arrival_port + k) % other.degree] is not None
            ):
                continue
            out.append((other.id, k))
    return out


def predict(tmap: TopoMap, h: Hypothesis, node: int, port: int) -> Prediction | None:
    """What ``h`` predicts for leaving ``node`` by ``port``; None if it cannot say."""
    img = h.image_port(tmap, node, port)
    if img is None:
        return None
    c, pc = img
    e = tmap.node(c).ports[pc]
    if e is None or e in h.cuts:
        return None
    edge = tmap.edge(e)
    w, q = edge.other_end(c, pc)
    return Prediction(w, q, edge.length_m, tmap.node(w).kind, e)


def arrival_matches(
    tmap: TopoMap,
    seen: Signature,
    arrival_port: int | None,
    pred: Prediction,
    length_m: float | None,
    tol: Tolerances,
) -> int | None:
    """The rotation under which the node ``seen`` is the predicted one, or None."""
    if not tol.length_ok(length_m, pred.length_m):
        return None
    if seen.kind != pred.kind:
        return None
    sig = tmap.signature(pred.node)
    for k in rotations(seen, sig, tol.clearance_m, tol.angle_rad):
        if arrival_port is None or (arrival_port + k) % tmap.node(pred.node).degree == (
            pred.arrival_port
        ):
            return k
    return None


def separating_port(tmap: TopoMap, hyps: Hypotheses, node: int) -> int | None:
    """The unexplored departure of ``node`` whose predictions split the live hypotheses into
    the most groups (the move that separates them fastest); None if no departure tests any."""
    best: tuple[int, float, int] | None = None
    best_port = None
    for p, e in enumerate(tmap.node(node).ports):
        if e is not None:
            continue
        keys: set[object] = set()
        known = 0
        lengths = []
        for h in hyps.live:
            pred = predict(tmap, h, node, p)
            if pred is None:
                keys.add(None)
            else:
                known += 1
                lengths.append(pred.length_m)
                keys.add((pred.node, pred.arrival_port))
        if known == 0:
            continue
        groups = len(keys)
        if groups < 2 and len(hyps.live) > 1:
            continue  # every hypothesis predicts the same: nothing to learn here
        score = (groups, -min(lengths), -p)
        if best is None or score > best:
            best, best_port = score, p
    return best_port

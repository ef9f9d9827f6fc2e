"""Score an exploration's topological map against the world's ground-truth GVG.

Works on plain data (the map as ``TopoMap.to_dict`` writes it, and the merges as node pairs with
the true positions of their first visits), so the simulator side never imports the algorithm.
A map node *is* the true node nearest to where it was first visited, within ``match_m``.

Coverage is judged on *places*: true meet points joined by an edge shorter than
``CLOSE_MEET_M`` are one place (section VII-B: a sonar robot sees such a pair as one junction
on one pass and as two on another, and homes onto whichever it reaches first), and an edge
between two of them is not one to find. A map covers the world when it holds every place and
an edge between every two places the true GVG joins (boundary points are places of their own).

An edge of the map between two places the true GVG does not join is *wrong*: the robot traced
past a junction without homing there, or took the node it arrived at for another. A wrong edge
is no merge, but it is how most copies begin: the old node whose departure it occupies is never
a candidate again when the robot comes to it by the true edge.
"""

from __future__ import annotations

import math
from collections import Counter
from collections.abc import Iterable, Mapping, Sequence
from typing import Any

import networkx as nx

from sim_backend.ground_truth import GroundTruthGVG

Pair = tuple[int, int, "tuple[float, float] | None", "tuple[float, float] | None"]

#: True meet points this close along an edge are one place (fig1's 0.20 m pair, fig14's
#: 0.26 and 0.29 m, fig16's weak meet point 0.36 m from the corridor's).
CLOSE_MEET_M = 0.4


def places(gvg: GroundTruthGVG, close_m: float = CLOSE_MEET_M) -> dict[int, int]:
    """True node id -> the id of its place (the smallest id among the meet points it is
    joined to by edges shorter than ``close_m``; a boundary point is its own place)."""
    g = nx.Graph()
    g.add_nodes_from(n.id for n in gvg.nodes)
    meets = {n.id for n in gvg.meet_points}
    g.add_edges_from(
        (e.u, e.v) for e in gvg.edges if e.u in meets and e.v in meets and e.length_m < close_m
    )
    return {n: min(c) for c in nx.connected_components(g) for n in c}


def true_node_of(
    gvg: GroundTruthGVG,
    truth: Sequence[float] | Mapping[str, float] | None,
    kind: str,
    match_m: float,
) -> int | None:
    """The ground-truth node a map node stands for, or None if nothing true is near."""
    if truth is None:
        return None
    x, y = (truth["x"], truth["y"]) if isinstance(truth, Mapping) else truth
    node = gvg.nearest_node(x, y, kind=kind)
    if node is None or math.hypot(node.x - x, node.y - y) > match_m:
        return None
    return node.id


def cycle_rank(n_nodes: int, edges: Iterable[tuple[int, int]], nodes: Iterable[int]) -> int:
    """Independent cycles of a graph: E - V + components (the loops to close)."""
    g = nx.MultiGraph()
    g.add_nodes_from(nodes)
    g.add_edges_from(edges)
    return g.number_of_edges() - n_nodes + nx.number_connected_components(g)


def score_exploration(
    gvg: GroundTruthGVG,
    map_data: Mapping[str, Any],
    merges: Iterable[Sequence[Pair]],
    match_m: float = 0.75,
) -> dict[str, Any]:
    nodes = map_data["nodes"]
    edges = map_data["edges"]
    true_of: dict[int, int | None] = {
        n["id"]: true_node_of(gvg, n.get("truth"), n["kind"], match_m) for n in nodes
    }
    meet_ids = {n.id for n in gvg.meet_points}
    found_meets = {t for n in nodes if n["kind"] == "meet" and (t := true_of[n["id"]]) in meet_ids}
    per_true: dict[int, int] = {}
    for n in nodes:
        t = true_of[n["id"]]
        if t is not None:
            per_true[t] = per_true.get(t, 0) + 1
    true_pairs = {frozenset((e.u, e.v)) for e in gvg.edges}
    place = places(gvg)
    found_pairs = set()
    mapped_links: Counter[frozenset[int]] = Counter()
    for e in edges:
        a, b = true_of.get(e["u"]), true_of.get(e["v"])
        if a is None or b is None:
            continue
        if frozenset((a, b)) in true_pairs:
            found_pairs.add(frozenset((a, b)))
        mapped_links[frozenset((place[a], place[b]))] += 1
    true_places = {place[t] for t in meet_ids}
    found_places = {place[t] for t in found_meets}
    # Two places can be joined twice (the two ways round a block): each edge is to find.
    true_links = Counter(
        link for e in gvg.edges if len(link := frozenset((place[e.u], place[e.v]))) == 2
    )
    n_links = sum(true_links.values())
    found_links = sum(min(n, mapped_links[link]) for link, n in true_links.items())
    wrong = sum(n for link, n in mapped_links.items() if len(link) == 2 and link not in true_links)
    false_merges = 0
    for record in merges:
        for _, _, td, tr in record:
            if td is None or tr is None:
                continue
            if math.hypot(td[0] - tr[0], td[1] - tr[1]) > 2.0 * match_m:
                false_merges += 1
    gvg_nodes = [n.id for n in gvg.nodes if n.kind in ("meet", "boundary")]
    gvg_edges = [(e.u, e.v) for e in gvg.edges]
    map_ids = [n["id"] for n in nodes]
    return {
        "true_meet_points": len(meet_ids),
        "found_meet_points": len(found_meets),
        "true_boundary_points": len(gvg.boundary_points),
        "map_meet_nodes": sum(n["kind"] == "meet" for n in nodes),
        "map_boundary_nodes": sum(n["kind"] == "boundary" for n in nodes),
        "duplicate_nodes": sum(c - 1 for c in per_true.values()),
        "unmatched_nodes": sum(t is None for t in true_of.values()),
        "true_edges": len(gvg.edges),
        "found_edges": len(found_pairs),
        "true_places": len(true_places),
        "found_places": len(found_places),
        "true_place_edges": n_links,
        "found_place_edges": found_links,
        "covered": found_places == true_places and found_links == n_links,
        "map_edges": len(edges),
        "wrong_edges": wrong,
        "loop_closures_true": cycle_rank(len(gvg_nodes), gvg_edges, gvg_nodes),
        "loop_closures_found": cycle_rank(
            len(map_ids), [(e["u"], e["v"]) for e in edges], map_ids
        ),
        "false_merges": false_merges,
        "ambiguous_nodes": sum(bool(n.get("ambiguous_with")) for n in nodes),
    }


def naive_baseline(
    arrivals: Iterable[tuple[float, float, int | None]], radius_m: float = 1.0
) -> dict[str, int]:
    """Section IV's naive method replayed on the same meet-point arrivals: a meet point is old
    if its dead-reckoned position lies within ``radius_m`` of one already seen.

    ``arrivals`` are (dead-reckoned x, y, true node id or None) in the order they happened.
    """
    seen: list[tuple[float, float, int | None]] = []
    false_merges = missed = closures = 0
    for x, y, true_id in arrivals:
        near = min(seen, key=lambda s: math.hypot(s[0] - x, s[1] - y), default=None)
        if near is not None and math.hypot(near[0] - x, near[1] - y) <= radius_m:
            if near[2] is not None and true_id is not None and near[2] != true_id:
                false_merges += 1
            else:
                closures += 1
            continue
        if true_id is not None and any(s[2] == true_id for s in seen):
            missed += 1
        seen.append((x, y, true_id))
    return {
        "nodes": len(seen),
        "revisits_recognised": closures,
        "false_merges": false_merges,
        "missed_revisits": missed,
        "radius_m": radius_m,
    }

"""Scoring a traced run against the ground-truth GVG (for ``tslam trace``).

Inputs are plain arrays and records, so the scorer knows nothing of the tracer:

- ``path``: ``(n, 3)`` true positions with the encoder distance at each (x, y, distance);
- ``nodes``: one record per node the robot reported: kind ("meet" | "boundary"), its true
  position at the moment it was reported, the degree it saw, the encoder distance then;
- ``edges``: one record per edge traversal: the indices of its end nodes in ``nodes`` and the
  length the robot measured. A traversal is scored against the true edge its path followed to
  the end node; one that followed none (it went through a junction without homing there) is
  counted in ``edges_not_in_ground_truth`` and not scored.
"""

from __future__ import annotations

import math
from collections import Counter
from dataclasses import dataclass

import numpy as np

from sim_backend.explore_scoring import places
from sim_backend.ground_truth import GroundTruthGVG
from sim_backend.world import point_segments_distance

ARRIVED_M = 0.5  # this close to a node, or to an edge, the robot is at it or on it
PASS_M = 0.25  # a robot this close to a meet point went through it


@dataclass(frozen=True)
class SeenNode:
    kind: str
    x: float
    y: float
    degree: int
    distance_m: float


@dataclass(frozen=True)
class SeenEdge:
    start: int
    end: int
    length_m: float


def score_trace(
    gvg: GroundTruthGVG,
    path: np.ndarray,
    nodes: list[SeenNode],
    edges: list[SeenEdge],
    skip_after_node_m: float = 0.5,
) -> dict[str, float | int | None]:
    """The figures of ``trace_report.json``."""
    report: dict[str, float | int | None] = {}
    # Edge error: the true path's distance from the true GVG, from the first node on, leaving
    # out the first ``skip_after_node_m`` after each node (where the robot leaves a node along
    # its departure before the laws take over).
    if nodes and len(path):
        node_d = np.array([n.distance_m for n in nodes])
        d = path[:, 2]
        after = d[:, None] - node_d[None, :]
        near_node = ((after >= 0) & (after < skip_after_node_m)).any(axis=1)
        keep = (d >= node_d.min()) & ~near_node
        err = gvg.distance_to(path[keep, :2]) if keep.any() else np.zeros(0)
    else:
        err = np.zeros(0)
    report["edge_samples"] = len(err)
    report["edge_error_median_m"] = _r(float(np.median(err))) if len(err) else None
    report["edge_error_p95_m"] = _r(float(np.percentile(err, 95))) if len(err) else None
    report["edge_error_max_m"] = _r(float(err.max())) if len(err) else None

    meets = [i for i, n in enumerate(nodes) if n.kind == "meet"]
    matched: dict[int, int] = {}
    errors, degree_ok = [], 0
    of_place = place_degrees(gvg)
    for i in meets:
        n = nodes[i]
        true = gvg.nearest_node(n.x, n.y, kind="meet")
        if true is None:
            continue
        matched[i] = true.id
        errors.append(math.hypot(n.x - true.x, n.y - true.y))
        # A meet point of a close pair may be read alone or with its place (section VII-B).
        degree_ok += int(n.degree in (true.degree, of_place[true.id]))
    report["meet_points_seen"] = len(meets)
    report["meet_point_error_max_m"] = _r(max(errors)) if errors else None
    report["meet_point_error_median_m"] = _r(float(np.median(errors))) if errors else None
    report["degree_match_ratio"] = _r(degree_ok / len(meets)) if meets else None
    visits, unhomed = _passes(gvg, path, [nodes[i] for i in meets])
    report["meet_point_passes"] = visits
    report["meet_point_passes_unhomed"] = unhomed

    rel, unmatched = [], 0
    for e in edges:
        u, v = matched.get(e.start), matched.get(e.end)
        if u is None or v is None or u == v:
            continue
        # The true edge is the one the robot went along to the end node, not the one joining
        # the two whose length is closest to what it measured: the robot can also go the long
        # way, through a junction it did not home onto (scored against the short edge, that
        # would read as a length error of the tracer's). Only the way up to its first
        # arrival at the end node counts: tracing on past the node and coming back is an
        # error of the length, to be scored.
        start, end = nodes[e.start], nodes[e.end]
        d = path[:, 2]
        way = path[(d >= start.distance_m) & (d <= end.distance_m), :2]
        near = min(ARRIVED_M, 0.4 * math.hypot(end.x - start.x, end.y - start.y))
        there = np.flatnonzero(np.hypot(way[:, 0] - end.x, way[:, 1] - end.y) <= near)
        if len(there):
            way = way[: there[0] + 1]
        along = [g for g in gvg.edges if {g.u, g.v} == {u, v} and _follows(way, g.points)]
        if not along:
            unmatched += 1  # the robot joined two meet points by no single true edge
            continue
        true_len = min(along, key=lambda g: abs(g.length_m - e.length_m)).length_m
        rel.append(abs(e.length_m - true_len) / true_len)
    report["meet_to_meet_edges"] = len(rel) + unmatched
    report["edges_not_in_ground_truth"] = unmatched
    report["edge_length_error_max_rel"] = _r(max(rel)) if rel else None
    report["edge_length_error_median_rel"] = _r(float(np.median(rel))) if rel else None
    return report


def place_degrees(gvg: GroundTruthGVG) -> dict[int, int]:
    """True meet point id -> the degree of its place (``explore_scoring.places``): the edges
    that leave the place, those between its own points left out. A point alone is its own."""
    place = places(gvg)
    out = Counter[int]()
    for e in gvg.edges:
        if place[e.u] != place[e.v]:
            out[place[e.u]] += 1
            out[place[e.v]] += 1
    return {n.id: out[place[n.id]] for n in gvg.meet_points}


def _passes(
    gvg: GroundTruthGVG, path: np.ndarray, meets: list[SeenNode], close_m: float = PASS_M
) -> tuple[int, int]:
    """How often the robot came within ``close_m`` of a true meet point, and how many of
    those passes reported no meet point there. A pass is one stay within ``ARRIVED_M`` of
    the point; one still going on when the run ends is left out (it may be homing yet).
    Passing a junction without homing is what sends exploration astray, and it happens a
    few times in a hundred passes: a figure over many passes tests a tracer change where a
    whole exploration's outcome is a coin flip."""
    visits = unhomed = 0
    if len(path) == 0:
        return 0, 0
    for g in gvg.meet_points:
        dist = np.hypot(path[:, 0] - g.x, path[:, 1] - g.y)
        inside = dist <= ARRIVED_M
        edges = np.flatnonzero(np.diff(inside.astype(np.int8)))
        starts = list(edges[~inside[edges]] + 1)
        ends = list(edges[inside[edges]] + 1)
        if inside[0]:
            starts.insert(0, 0)
        for a, b in zip(starts, ends, strict=False):  # an unfinished stay has no end
            if dist[a:b].min() > close_m:
                continue
            visits += 1
            lo, hi = path[a, 2], path[b - 1, 2]
            homed = any(
                lo <= n.distance_m <= hi and math.hypot(n.x - g.x, n.y - g.y) <= ARRIVED_M
                for n in meets
            )
            unhomed += int(not homed)
    return visits, unhomed


def _follows(way: np.ndarray, polyline: np.ndarray, within_m: float = ARRIVED_M) -> bool:
    """Whether nine in ten of the points ``way`` lie within ``within_m`` of ``polyline``."""
    if len(way) == 0:
        return True  # nothing recorded between the two nodes: no evidence either way
    d = point_segments_distance(way, np.hstack([polyline[:-1], polyline[1:]]))
    return float(np.mean(d <= within_m)) >= 0.9


def _r(x: float) -> float:
    return round(x, 4)

"""Where the robot got to when it went past the node it expected without homing there.

A weak meet point (section VII-B; fig16's shallow indent) shows on one pass and not on the
next: a robot sent along a known edge can trace straight through the junction at its end and
arrive one or two edges further on, where the edge lengths say nothing fits. The dead-reckoned
path of this one traversal is good to a few centimetres over those few metres, so it says
which way the robot turned where it passed each junction; the map's departure angles there,
taken relative to the port the robot came in by, say which departure that turn was. Walking
the map that way, edge by edge, ends either at a mapped node (then its signature has the last
word) or on a departure nobody has explored yet (then what the robot found is a new node at
its end).

The walk gives up rather than guesses: every turn must fit one departure clearly better than
any other, and the lengths must add up.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from tslam.core.edgepaths import EdgePath
from tslam.core.frames import TAU
from tslam.core.localize import Tolerances
from tslam.core.topomap import TopoMap


@dataclass(frozen=True)
class WalkParams:
    look_m: float = 0.8  # the stretch of path either side of a junction that gives its bearing
    look_share: float = 0.7  # ... at most this share of a short edge, which turns again soon
    min_look_m: float = 0.2
    angle_rad: float = math.radians(35.0)  # a turn fits a departure within this ...
    margin_rad: float = math.radians(20.0)  # ... and clearly better than any other
    min_rest_m: float = 0.3  # beyond the junction: less is as likely the junction itself
    max_edges: int = 3
    # A departure not held: the path went this far from its start, then came back this close.
    out_m: float = 0.15
    back_m: float = 0.1


@dataclass(frozen=True)
class Walk:
    """``known``: the robot is at ``node``, come in by ``port``. Otherwise it left ``node`` by
    the unexplored ``port`` and found something new ``rest_m`` metres on."""

    node: int
    port: int
    known: bool
    rest_m: float
    passed: tuple[int, ...]  # the junctions gone through without homing, in order


def walk_on(
    tmap: TopoMap,
    start: int,
    port: int,
    path: EdgePath,
    length_m: float,
    tol: Tolerances,
    p: WalkParams | None = None,
) -> Walk | None:
    """Follow ``path`` (traced from ``start`` by ``port``, ``length_m`` metres long) through
    the map beyond the end of that port's edge; None if the path does not single out a way."""
    p = p or WalkParams()
    e = tmap.node(start).ports[port]
    if e is None or not tol.length_ok(path.length_m, length_m):
        return None  # ... or the record is not of this whole traversal
    edge = tmap.edge(e)
    w, q = edge.other_end(start, port)
    return _walk(tmap, w, q, edge.length_m, edge.length_m, path, length_m, tol, p)


def walk_back(
    tmap: TopoMap,
    start: int,
    port: int,
    path: EdgePath,
    length_m: float,
    tol: Tolerances,
    p: WalkParams | None = None,
) -> Walk | None:
    """The departure ``port`` of ``start`` was not held: ``path`` went out by it, came back
    through ``start`` without homing, and left by another departure. Where it went from
    there, as ``walk_on``; None if the path never came back, or does not say where it went."""
    p = p or WalkParams()
    if not tol.length_ok(path.length_m, length_m):
        return None
    s0 = _return(path, p)
    if s0 is None:
        return None
    return _walk(tmap, start, port, s0, s0 / 2.0, path, length_m, tol, p)


def _return(path: EdgePath, p: WalkParams) -> float | None:
    """Metres along ``path`` where it came back closest by its start, after going out."""
    _, x0, y0 = path.points[0]
    out = False
    best: tuple[float, float] | None = None
    for s, x, y in path.points:
        d = math.hypot(x - x0, y - y0)
        if not out:
            out = d >= p.out_m
        elif d <= p.back_m and (best is None or d < best[1]):
            best = (s, d)
        elif best is not None:
            break
    return None if best is None else best[0]


def _walk(
    tmap: TopoMap,
    w: int,
    q: int,
    s: float,
    came: float,
    path: EdgePath,
    length_m: float,
    tol: Tolerances,
    p: WalkParams,
) -> Walk | None:
    """From node ``w``, come in by port ``q`` ``s`` metres along ``path`` after ``came``
    metres on the edge before, edge by edge to where the path ends."""
    passed: list[int] = []
    for _ in range(p.max_edges):
        node = tmap.node(w)
        rest = length_m - s
        if node.kind != "meet" or rest < p.min_rest_m:
            return None
        out = _turn(path, s, came, rest, tmap, w, q, p)
        if out is None:
            return None
        passed.append(w)
        e2 = node.ports[out]
        if e2 is None:
            return Walk(w, out, False, rest, tuple(passed))
        nxt = tmap.edge(e2)
        w, q = nxt.other_end(w, out)
        s, came = s + nxt.length_m, nxt.length_m
        if tol.length_ok(length_m, s):
            return Walk(w, q, True, 0.0, tuple(passed))
        if length_m < s:
            return None
    return None


def _turn(
    path: EdgePath,
    s: float,
    came_m: float,
    rest_m: float,
    tmap: TopoMap,
    w: int,
    q: int,
    p: WalkParams,
) -> int | None:
    """The departure of node ``w`` (come in by port ``q``) that the path took ``s`` metres
    from its start, judged by the turn between the stretch before and the stretch after. The
    stretch after is kept within each departure's own edge, which may turn again soon."""
    node = tmap.node(w)
    x, y = path.at(s)
    bx, by = path.at(s - max(p.min_look_m, min(p.look_m, p.look_share * came_m, s)))
    back = math.atan2(by - y, bx - x)
    deps = node.departures_rad
    fits = []
    for k in range(node.degree):
        if k == q:
            continue
        e = node.ports[k]
        span = rest_m if e is None else min(rest_m, tmap.edge(e).length_m)
        ax, ay = path.at(s + max(p.min_look_m, min(p.look_m, p.look_share * span)))
        turn = math.atan2(ay - y, ax - x) - back
        fits.append((_angdiff(deps[k] - deps[q], turn), k))
    fits.sort()
    if not fits or fits[0][0] > p.angle_rad:
        return None
    if len(fits) > 1 and fits[1][0] - fits[0][0] < p.margin_rad:
        return None
    return fits[0][1]


def _angdiff(a: float, b: float) -> float:
    d = (a - b) % TAU
    return min(d, TAU - d)

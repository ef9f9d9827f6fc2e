"""Topological maps on disk (versioned JSON) and as pictures (SVG).

The core map knows nothing of files; this module adds the I/O around ``TopoMap.to_dict`` and
``from_dict``. Every failure to read a map, from a missing file to a port that names the wrong
edge, surfaces as one ``MapFormatError`` whose message starts with the file's path, so a
command can print it as one line.

Two drawings: ``odometry`` puts each node at its dead-reckoned pose of first visit, which
shows how the map and the robot's belief drift apart (the paper's Figs. 7 and 13);
``topological`` ignores poses and lays the graph out from edge lengths alone, which is all
the localization ever uses.
"""

from __future__ import annotations

import json
import math
import statistics
from collections.abc import Callable
from pathlib import Path

import networkx as nx

from sim_backend.svg import BOUNDARY_FILL, EDGE_STROKE, MEET_FILL, SvgCanvas
from tslam.core.topomap import MapFormatError, Node, TopoMap
from tslam.programs.output import write_text_atomic

__all__ = [
    "LAYOUTS",
    "MapFormatError",
    "load_map",
    "map_to_json",
    "render_map_svg",
    "save_map",
    "save_map_svg",
]

LAYOUTS = ("odometry", "topological")
UNEXPLORED_STROKE = "#e07b00"
AMBIGUOUS_STROKE = "#8a3ffc"
TRUTH_STROKE = "#111111"

Point = tuple[float, float]
Background = Callable[[SvgCanvas], None]


def map_to_json(topomap: TopoMap) -> str:
    return json.dumps(topomap.to_dict(), indent=1, allow_nan=False) + "\n"


def save_map(path: str | Path, topomap: TopoMap) -> None:
    """Write atomically, world-readable: a crash never leaves half a map behind.

    An unwritable path raises the programs' ``UserError`` (from ``write_text_atomic``).
    """
    write_text_atomic(path, map_to_json(topomap))


def load_map(path: str | Path) -> TopoMap:
    """Read a map written by ``save_map``; any problem is a ``MapFormatError`` naming the file."""
    p = Path(path)
    try:
        text = p.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise MapFormatError(f"{p}: no such file") from None
    except (OSError, UnicodeDecodeError) as exc:
        why = getattr(exc, "strerror", None) or str(exc)
        raise MapFormatError(f"{p}: cannot read: {why}") from None
    try:
        data = json.loads(text)
    except json.JSONDecodeError as exc:
        raise MapFormatError(
            f"{p}: not JSON: {exc.msg} at line {exc.lineno} column {exc.colno}"
        ) from None
    except RecursionError:
        raise MapFormatError(f"{p}: not a map: JSON nested too deeply") from None
    try:
        return TopoMap.from_dict(data)
    except MapFormatError as exc:
        raise MapFormatError(f"{p}: {exc}") from None


# -- drawing ---------------------------------------------------------------------------------


def render_map_svg(
    topomap: TopoMap,
    *,
    layout: str = "odometry",
    background: Background | None = None,
    bounds: tuple[float, float, float, float] | None = None,
    px_per_m: float = 40.0,
    show_truth: bool = False,
) -> str:
    """The map as SVG text: one marker per node (class ``map-meet`` / ``map-boundary``), its
    id as a label, edges, unexplored departures as short stubs, ambiguous nodes ringed.

    ``background(canvas)`` is called before the map is drawn, in the same metres: pass the
    world's ``bounds`` and draw walls and the ground-truth GVG there (``sim_backend.svg``).
    ``show_truth`` joins each node's pose to its true position, where known.
    """
    if layout not in LAYOUTS:
        raise ValueError(f"layout must be one of {', '.join(LAYOUTS)}, not {layout!r}")
    pos = _odometry_positions(topomap) if layout == "odometry" else _topological_positions(topomap)
    truth = show_truth and layout == "odometry"
    canvas = SvgCanvas(_bounds(topomap, pos, bounds, truth), px_per_m=px_per_m)
    if background is not None:
        background(canvas)
    r = max(0.06, 7.0 / px_per_m)
    with canvas.group(f"topological map, {layout} layout", class_="topomap"):
        _draw_edges(canvas, topomap, pos, layout, r)
        for node in topomap.nodes():
            _draw_node(canvas, node, pos[node.id], r, truth)
    return canvas.to_string()


def save_map_svg(
    path: str | Path,
    topomap: TopoMap,
    *,
    layout: str = "odometry",
    background: Background | None = None,
    bounds: tuple[float, float, float, float] | None = None,
    px_per_m: float = 40.0,
    show_truth: bool = False,
) -> None:
    """``render_map_svg`` to a file, atomically and world-readable like the other outputs."""
    svg = render_map_svg(
        topomap,
        layout=layout,
        background=background,
        bounds=bounds,
        px_per_m=px_per_m,
        show_truth=show_truth,
    )
    write_text_atomic(path, svg)


def _odometry_positions(m: TopoMap) -> dict[int, Point]:
    return {n.id: n.pose for n in m.nodes()}


def _topological_positions(m: TopoMap) -> dict[int, Point]:
    """Kamada-Kawai per connected component, scaled back to metres, components side by side.

    Kamada-Kawai is deterministic (it starts from a circle) and tries to make drawn distances
    the graph distances, so with edge lengths as weights the picture reads in metres.
    """
    g = nx.Graph()
    g.add_nodes_from(n.id for n in m.nodes())
    for e in m.edges():
        if e.u != e.v:
            w = max(e.length_m, 0.1)  # a zero distance between two nodes breaks the layout
            if g.has_edge(e.u, e.v):
                w = min(w, g.edges[e.u, e.v]["weight"])
            g.add_edge(e.u, e.v, weight=w)
    out: dict[int, Point] = {}
    x0 = 0.0
    for comp in sorted(nx.connected_components(g), key=min):
        sub = g.subgraph(sorted(comp))
        if len(sub) == 1:
            local = {next(iter(sub)): (0.0, 0.0)}
        else:
            raw = nx.kamada_kawai_layout(sub, weight="weight")
            ratios = [
                w / d
                for u, v, w in sub.edges(data="weight")
                if (d := math.dist(raw[u], raw[v])) > 1e-9
            ]
            s = statistics.median(ratios) if ratios else 1.0
            local = {n: (float(p[0]) * s, float(p[1]) * s) for n, p in raw.items()}
        xs = [p[0] for p in local.values()]
        shift = x0 - min(xs)
        out.update({n: (x + shift, y) for n, (x, y) in local.items()})
        x0 += max(xs) - min(xs) + 2.0
    return out


def _bounds(
    m: TopoMap,
    pos: dict[int, Point],
    given: tuple[float, float, float, float] | None,
    truth: bool,
) -> tuple[float, float, float, float]:
    """The map's extent with a metre to spare for stubs, loops and labels, grown to ``given``."""
    pts = list(pos.values())
    if truth:
        pts += [n.truth for n in m.nodes() if n.truth is not None]
    boxes = []
    if pts:
        xs, ys = [p[0] for p in pts], [p[1] for p in pts]
        boxes.append((min(xs) - 1.0, min(ys) - 1.0, max(xs) + 1.0, max(ys) + 1.0))
    if given is not None:
        boxes.append(tuple(float(b) for b in given))
    if not boxes:
        return (0.0, 0.0, 1.0, 1.0)
    return (
        min(b[0] for b in boxes),
        min(b[1] for b in boxes),
        max(b[2] for b in boxes),
        max(b[3] for b in boxes),
    )


def _unit(a: float) -> Point:
    return math.cos(a), math.sin(a)


def _bezier(p0: Point, p1: Point, p2: Point, p3: Point, n: int = 16) -> list[Point]:
    out = []
    for i in range(n + 1):
        t = i / n
        a, b, c, d = (1 - t) ** 3, 3 * (1 - t) ** 2 * t, 3 * (1 - t) * t**2, t**3
        out.append(
            (
                a * p0[0] + b * p1[0] + c * p2[0] + d * p3[0],
                a * p0[1] + b * p1[1] + c * p2[1] + d * p3[1],
            )
        )
    return out


def _draw_edges(
    canvas: SvgCanvas, m: TopoMap, pos: dict[int, Point], layout: str, r: float
) -> None:
    """Edges leave along their departures in the odometry layout, so a drawing looks like the
    GVG it came from; in the topological layout departures mean nothing, so parallel edges
    are bowed apart instead. Self-loops use their departures in both."""
    siblings: dict[tuple[int, int], list[int]] = {}
    for e in m.edges():
        siblings.setdefault((min(e.u, e.v), max(e.u, e.v)), []).append(e.id)
    for e in m.edges():
        pu, pv = pos[e.u], pos[e.v]
        chord = math.dist(pu, pv)
        du = m.node(e.u).departures_rad[e.port_u]
        dv = m.node(e.v).departures_rad[e.port_v]
        if e.u == e.v:
            reach = min(max(0.3 * e.length_m, 4 * r), 1.5)
        elif layout == "odometry":
            reach = 0.4 * chord
        else:
            group = siblings[(min(e.u, e.v), max(e.u, e.v))]
            bow = 0.5 * (group.index(e.id) - (len(group) - 1) / 2)
            ang = math.atan2(pv[1] - pu[1], pv[0] - pu[0])
            du, dv, reach = ang + bow, ang + math.pi - bow, 0.4 * chord
        tu, tv = _unit(du), _unit(dv)
        pts = _bezier(
            pu,
            (pu[0] + reach * tu[0], pu[1] + reach * tu[1]),
            (pv[0] + reach * tv[0], pv[1] + reach * tv[1]),
            pv,
        )
        n = len(e.lengths_m)
        canvas.polyline(
            pts,
            stroke=EDGE_STROKE,
            stroke_width=2,
            class_="map-edge",
            title=f"edge {e.id}: {e.u}-{e.v}, {e.length_m:.2f} m ({n} measurement"
            + ("s)" if n != 1 else ")"),
        )
    for n, p in m.unexplored():
        node, (x, y) = m.node(n), pos[n]
        tx, ty = _unit(node.departures_rad[p])
        canvas.polyline(
            [(x, y), (x + 3 * r * tx, y + 3 * r * ty)],
            stroke=UNEXPLORED_STROKE,
            stroke_width=2,
            stroke_dasharray="3,2",
            class_="map-unexplored",
            title=f"node {n} port {p}: unexplored",
        )


def _draw_node(canvas: SvgCanvas, node: Node, p: Point, r: float, truth: bool) -> None:
    x, y = p
    tip = (
        f"{node.kind} {node.id}: clearance {node.clearance_m:.2f} m, degree {node.degree},"
        " departures " + " ".join(f"{math.degrees(a):.0f}" for a in node.departures_rad)
    )
    if node.ambiguous_with:
        tip += ", ambiguous with " + " ".join(str(o) for o in sorted(node.ambiguous_with))
        canvas.circle(
            x,
            y,
            1.8 * r,
            fill="none",
            stroke=AMBIGUOUS_STROKE,
            stroke_width=2,
            stroke_dasharray="4,2",
            class_="map-ambiguous",
        )
    if truth and node.truth is not None:
        tx, ty = node.truth
        canvas.polyline(
            [(x, y), (tx, ty)],
            stroke=TRUTH_STROKE,
            stroke_width=1,
            stroke_dasharray="2,2",
            class_="map-truth",
            title=f"node {node.id}: true position ({tx:.2f}, {ty:.2f})",
        )
    if node.kind == "meet":
        canvas.circle(x, y, r, fill=MEET_FILL, stroke="#ffffff", class_="map-meet", title=tip)
    else:
        canvas.rect(
            x - r, y - r, 2 * r, 2 * r, fill=BOUNDARY_FILL, class_="map-boundary", title=tip
        )
    canvas.text(x + 1.2 * r, y + 1.2 * r, str(node.id), font_size=11, class_="map-label")

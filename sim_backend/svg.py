"""A small dependency-free SVG writer, and drawings of worlds and their GVGs.

Pictures are for people checking a world or a scored run by eye, so the writer stays tiny:
callers speak world metres with y up, the canvas flips to SVG pixels (y down) in one place,
and every element class is stable so tests and scripts can count what was drawn.
"""

from __future__ import annotations

import contextlib
import math
import os
import re
import tempfile
from collections.abc import Iterable, Iterator
from typing import TYPE_CHECKING

import numpy as np

from sim_backend.world import GridWorld, PolygonWorld, World

if TYPE_CHECKING:
    from sim_backend.ground_truth import GroundTruthGVG

__all__ = ["SvgCanvas", "draw_gvg", "draw_world", "render_world_svg"]

# XML 1.0 forbids most control characters even when escaped: drop them from text.
_XML_INVALID = re.compile("[\x00-\x08\x0b\x0c\x0e-\x1f\ufffe\uffff]")

FREE_FILL = "#f4f1e8"
OBSTACLE_FILL = "#4a4a4a"
WALL_STROKE = "#111111"
EDGE_STROKE = "#1f6fd1"
MEET_FILL = "#d1311f"
BOUNDARY_FILL = "#2a9d3a"
HORIZON_FILL = "#e0a800"
LOOP_FILL = "#8a3ffc"
START_FILL = "#000000"


def _escape_text(s: str) -> str:
    s = _XML_INVALID.sub("", str(s))
    return s.replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;")


def _escape_attr(s: str) -> str:
    return _escape_text(s).replace('"', "&quot;").replace("\n", "&#10;").replace("\t", "&#9;")


def _fmt(v: float) -> str:
    """Pixels to 1/100: finer than any screen, and keeps files small and diffable."""
    if not math.isfinite(v):
        raise ValueError(f"non-finite coordinate {v!r} cannot be drawn")
    out = f"{v:.2f}".rstrip("0").rstrip(".")
    return "0" if out in ("-0", "") else out


def _attrs(style: dict[str, object]) -> str:
    """``stroke_width=2`` -> ``stroke-width="2"``; a trailing underscore (``class_``) is
    dropped so Python keywords can be used; ``None`` values are omitted."""
    parts = []
    for key, value in style.items():
        if value is None:
            continue
        name = key.rstrip("_").replace("_", "-")
        if isinstance(value, float):
            value = _fmt(value)
        parts.append(f' {name}="{_escape_attr(str(value))}"')
    return "".join(parts)


class SvgCanvas:
    """An SVG drawing in world coordinates: metres, y up, ``bounds`` plus a margin.

    Lengths given in metres (positions, radii, rectangle sizes) are scaled; style values
    (stroke widths, font sizes) are in pixels so lines stay legible at any world size.
    Shapes accept ``title=...``: a tooltip, handy for inspecting nodes in a browser.
    """

    def __init__(
        self,
        bounds: tuple[float, float, float, float],
        px_per_m: float = 40.0,
        margin_m: float = 0.5,
    ) -> None:
        xmin, ymin, xmax, ymax = (float(b) for b in bounds)
        if not (xmax > xmin and ymax > ymin):
            raise ValueError(f"bounds must have positive width and height, got {bounds}")
        if not (px_per_m > 0 and margin_m >= 0):
            raise ValueError("px_per_m must be positive and margin_m non-negative")
        self.bounds = (xmin, ymin, xmax, ymax)
        self.px_per_m = float(px_per_m)
        self.margin_m = float(margin_m)
        self.width_px = (xmax - xmin + 2 * margin_m) * px_per_m
        self.height_px = (ymax - ymin + 2 * margin_m) * px_per_m
        self._body: list[str] = []
        self._open_groups = 0

    # -- coordinates -----------------------------------------------------------------------

    def px(self, x: float, y: float) -> tuple[float, float]:
        """World metres (y up) to SVG pixels (y down)."""
        xmin, _, _, ymax = self.bounds
        return (
            (x - xmin + self.margin_m) * self.px_per_m,
            (ymax + self.margin_m - y) * self.px_per_m,
        )

    def _points(self, points: Iterable[Iterable[float]]) -> str:
        arr = np.asarray(list(points) if not isinstance(points, np.ndarray) else points, float)
        arr = arr.reshape(-1, 2)
        return " ".join(f"{_fmt(px)},{_fmt(py)}" for px, py in (self.px(x, y) for x, y in arr))

    def _emit(self, tag: str, attrs: dict[str, object], title: str | None, text: str = "") -> None:
        inner = (f"<title>{_escape_text(title)}</title>" if title is not None else "") + text
        if inner:
            self._body.append(f"<{tag}{_attrs(attrs)}>{inner}</{tag}>")
        else:
            self._body.append(f"<{tag}{_attrs(attrs)}/>")

    # -- shapes ------------------------------------------------------------------------------

    def polygon(
        self, points: Iterable[Iterable[float]], *, title: str | None = None, **style: object
    ) -> None:
        self._emit("polygon", {"points": self._points(points), **style}, title)

    def polyline(
        self, points: Iterable[Iterable[float]], *, title: str | None = None, **style: object
    ) -> None:
        style.setdefault("fill", "none")
        self._emit("polyline", {"points": self._points(points), **style}, title)

    def path_rings(
        self,
        rings: Iterable[Iterable[Iterable[float]]],
        *,
        title: str | None = None,
        **style: object,
    ) -> None:
        """Closed rings as one even-odd path, so polygons with holes fill correctly."""
        d = []
        for ring in rings:
            pts = self._points(ring).split(" ")
            if pts and pts[0]:
                d.append("M" + " L".join(pts) + " Z")
        style.setdefault("fill_rule", "evenodd")
        self._emit("path", {"d": " ".join(d), **style}, title)

    def segments(self, segs: np.ndarray, *, title: str | None = None, **style: object) -> None:
        """Many line segments ``(N, 4)`` as a single path element (walls, rays)."""
        segs = np.asarray(segs, dtype=float).reshape(-1, 4)
        d = []
        for x1, y1, x2, y2 in segs:
            a, b = self.px(x1, y1), self.px(x2, y2)
            d.append(f"M{_fmt(a[0])},{_fmt(a[1])} L{_fmt(b[0])},{_fmt(b[1])}")
        style.setdefault("fill", "none")
        self._emit("path", {"d": " ".join(d), **style}, title)

    def circle(
        self, x: float, y: float, r_m: float, *, title: str | None = None, **style: object
    ) -> None:
        cx, cy = self.px(x, y)
        self._emit("circle", {"cx": cx, "cy": cy, "r": r_m * self.px_per_m, **style}, title)

    def rect(
        self,
        x: float,
        y: float,
        w_m: float,
        h_m: float,
        *,
        title: str | None = None,
        **style: object,
    ) -> None:
        """Axis-aligned rectangle whose lower-left world corner is ``(x, y)``."""
        left, top = self.px(x, y + h_m)
        attrs = {
            "x": left,
            "y": top,
            "width": w_m * self.px_per_m,
            "height": h_m * self.px_per_m,
            **style,
        }
        self._emit("rect", attrs, title)

    def text(
        self, x: float, y: float, s: str, *, title: str | None = None, **style: object
    ) -> None:
        tx, ty = self.px(x, y)
        style.setdefault("font_family", "sans-serif")
        style.setdefault("font_size", 12)
        self._emit("text", {"x": tx, "y": ty, **style}, title, _escape_text(s))

    @contextlib.contextmanager
    def group(self, title: str | None = None, **style: object) -> Iterator[SvgCanvas]:
        """``with canvas.group("walls", class_="walls"):`` wraps what is drawn inside."""
        head = f"<g{_attrs(style)}>"
        if title is not None:
            head += f"<title>{_escape_text(title)}</title>"
        self._body.append(head)
        self._open_groups += 1
        try:
            yield self
        finally:
            self._body.append("</g>")
            self._open_groups -= 1

    # -- output ------------------------------------------------------------------------------

    def to_string(self) -> str:
        if self._open_groups:
            raise RuntimeError("to_string() called inside an open group")
        w, h = _fmt(self.width_px), _fmt(self.height_px)
        head = (
            '<?xml version="1.0" encoding="UTF-8"?>\n'
            f'<svg xmlns="http://www.w3.org/2000/svg" version="1.1" width="{w}" height="{h}"'
            f' viewBox="0 0 {w} {h}">\n'
        )
        return head + "\n".join(self._body) + "\n</svg>\n"

    def save(self, path: str | os.PathLike[str]) -> None:
        """Write atomically: readers (a browser, a CI artefact upload) never see half a file."""
        text = self.to_string()
        target = os.fspath(path)
        directory = os.path.dirname(os.path.abspath(target))
        fd, tmp = tempfile.mkstemp(prefix=".svg-", suffix=".tmp", dir=directory)
        try:
            with os.fdopen(fd, "w", encoding="utf-8") as fh:
                fh.write(text)
            os.chmod(tmp, 0o644)  # mkstemp makes it private; a picture is meant to be shared
            os.replace(tmp, target)
        except BaseException:
            with contextlib.suppress(OSError):
                os.unlink(tmp)
            raise


def draw_world(canvas: SvgCanvas, world: World) -> None:
    """Obstacles dark, free space light, walls stroked on top."""
    xmin, ymin, xmax, ymax = canvas.bounds
    m = canvas.margin_m
    with canvas.group(f"world {world.name}", class_="world"):
        canvas.rect(
            xmin - m,
            ymin - m,
            xmax - xmin + 2 * m,
            ymax - ymin + 2 * m,
            fill=OBSTACLE_FILL,
            class_="obstacle",
        )
        if isinstance(world, PolygonWorld):
            geoms = getattr(world.free_region, "geoms", [world.free_region])
            for poly in geoms:
                rings = [np.asarray(poly.exterior.coords)[:-1]]
                rings += [np.asarray(r.coords)[:-1] for r in poly.interiors]
                canvas.path_rings(rings, fill=FREE_FILL, class_="free")
        elif isinstance(world, GridWorld):
            _draw_free_cells(canvas, world)
        canvas.segments(world.segments, stroke=WALL_STROKE, stroke_width=1.5, class_="walls")


def _draw_free_cells(canvas: SvgCanvas, world: GridWorld) -> None:
    """Free cells as one rectangle per horizontal run: far fewer elements than cells."""
    free = ~world.occupied
    res = world.resolution_m
    ox, oy = world.origin
    padded = np.zeros((free.shape[0], free.shape[1] + 2), dtype=np.int8)
    padded[:, 1:-1] = free
    step = np.diff(padded, axis=1)
    rows_s, cols_s = np.nonzero(step == 1)
    _, cols_e = np.nonzero(step == -1)  # row-major order: the k-th end closes the k-th start
    for r, c0, c1 in zip(rows_s.tolist(), cols_s.tolist(), cols_e.tolist(), strict=True):
        canvas.rect(
            ox + c0 * res,
            oy + r * res,
            (c1 - c0) * res,
            res,
            fill=FREE_FILL,
            class_="free",
        )


def draw_gvg(canvas: SvgCanvas, gvg: GroundTruthGVG, node_radius_m: float | None = None) -> None:
    """Edges as polylines; meet points as filled circles labelled with their degree,
    boundary points as squares, horizon ends as diamonds, loop nodes as small circles; the
    start as a black ring and the access point as a cross."""
    r = node_radius_m if node_radius_m is not None else max(0.06, 8.0 / canvas.px_per_m)
    with canvas.group("GVG", class_="gvg"):
        for e in gvg.edges:
            canvas.polyline(
                e.points,
                stroke=EDGE_STROKE,
                stroke_width=2,
                stroke_linejoin="round",
                class_="gvg-edge",
                title=f"edge {e.id}: {e.u}-{e.v}, {e.length_m:.2f} m",
            )
        for n in gvg.nodes:
            tip = f"{n.kind} {n.id} ({n.x:.2f}, {n.y:.2f}) clearance {n.clearance_m:.2f} m"
            if n.reason:
                tip += f", {n.reason}"
            if n.kind == "meet":
                tip += ", departures " + " ".join(
                    f"{math.degrees(a):.0f}" for a in n.departure_angles
                )
                canvas.circle(
                    n.x, n.y, r, fill=MEET_FILL, stroke="#ffffff", class_="gvg-meet", title=tip
                )
                canvas.text(
                    n.x + 1.1 * r,
                    n.y + 1.1 * r,
                    str(n.degree),
                    font_size=11,
                    fill=MEET_FILL,
                    class_="gvg-meet-label",
                )
            elif n.kind == "boundary":
                canvas.rect(
                    n.x - r,
                    n.y - r,
                    2 * r,
                    2 * r,
                    fill=BOUNDARY_FILL,
                    class_="gvg-boundary",
                    title=tip,
                )
            elif n.kind == "horizon":
                diamond = [
                    (n.x + r * 1.3, n.y),
                    (n.x, n.y + r * 1.3),
                    (n.x - r * 1.3, n.y),
                    (n.x, n.y - r * 1.3),
                ]
                canvas.polygon(diamond, fill=HORIZON_FILL, class_="gvg-horizon", title=tip)
            else:
                canvas.circle(n.x, n.y, 0.6 * r, fill=LOOP_FILL, class_="gvg-loop", title=tip)
        if gvg.start is not None:
            sx, sy = gvg.start
            canvas.circle(
                sx,
                sy,
                1.5 * r,
                fill="none",
                stroke=START_FILL,
                stroke_width=2,
                class_="start",
                title=f"start ({sx:.2f}, {sy:.2f})",
            )
        if gvg.access_point is not None:
            ax, ay = gvg.access_point
            canvas.segments(
                np.array([[ax - r, ay - r, ax + r, ay + r], [ax - r, ay + r, ax + r, ay - r]]),
                stroke=START_FILL,
                stroke_width=2,
                class_="access",
                title=f"access point ({ax:.2f}, {ay:.2f})",
            )


def render_world_svg(
    world: World,
    gvg: GroundTruthGVG | None,
    path: str | os.PathLike[str] | None = None,
    *,
    px_per_m: float = 40.0,
    margin_m: float = 0.5,
) -> str:
    """Draw ``world`` (and ``gvg`` if given); save to ``path`` unless it is None.

    Returns the SVG text either way, so callers with their own atomic writer can use it.
    """
    canvas = SvgCanvas(world.bounds, px_per_m=px_per_m, margin_m=margin_m)
    draw_world(canvas, world)
    if gvg is not None:
        draw_gvg(canvas, gvg)
    else:
        sx, sy = world.start.x, world.start.y
        canvas.circle(
            sx,
            sy,
            0.15,
            fill="none",
            stroke=START_FILL,
            stroke_width=2,
            class_="start",
            title=f"start ({sx:.2f}, {sy:.2f})",
        )
    text = canvas.to_string()
    if path is not None:
        canvas.save(path)
    return text

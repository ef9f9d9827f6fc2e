"""Static planar worlds: the geometry every simulated sensor and the ground truth read.

A world is free space in the plane, in metres. Two kinds exist behind one interface:

- ``PolygonWorld``: a boundary polygon minus obstacle polygons (the polygon JSON format);
- ``GridWorld``: an occupancy grid (the ROS map_server format), a cell being free or occupied.

Both expose the same derived geometry, computed once at construction:

- ``segments``: every wall edge of free space, an ``(N, 4)`` float64 array ``x1, y1, x2, y2``;
  overlapping obstacles and obstacles crossing the boundary are resolved first, so each
  segment separates free space from obstacle;
- ``corners``: every vertex where two wall edges meet, ``(K, 2)``, with ``corner_convex``
  (``True`` where the obstacle pokes into free space, i.e. free space spans more than 180
  degrees around the vertex; these diffract sound weakly. ``False`` for the corners of a room,
  which reflect sound back like a corner reflector);
- ``is_free(points)``: vectorised membership test;
- ``free_area_m2`` and ``bounds``.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field

import numpy as np
import shapely
from shapely.geometry import MultiPolygon, Polygon
from shapely.ops import unary_union

from sim_backend.grid_walls import grid_walls, wall_tolerance


class WorldError(ValueError):
    """A world definition is unusable; the message names what is wrong."""


@dataclass(frozen=True)
class StartPose:
    """Where the robot starts, in the world frame: metres and radians."""

    x: float
    y: float
    theta: float = 0.0


@dataclass(eq=False)
class World:
    """Common geometry of a world. Build one with ``PolygonWorld`` or ``GridWorld``."""

    name: str
    start: StartPose
    source: str
    segments: np.ndarray = field(repr=False)
    corners: np.ndarray = field(repr=False)
    corner_convex: np.ndarray = field(repr=False)
    bounds: tuple[float, float, float, float]
    free_area_m2: float

    def is_free(self, points: np.ndarray) -> np.ndarray:
        """True for each ``(x, y)`` row of ``points`` that lies in free space."""
        raise NotImplementedError

    def check_start(self, robot_radius_m: float) -> None:
        """Raise WorldError unless a disk of ``robot_radius_m`` fits at the start pose."""
        p = np.array([[self.start.x, self.start.y]])
        if not bool(self.is_free(p)[0]):
            raise WorldError(f"start ({self.start.x:.3f}, {self.start.y:.3f}) is not in free space")
        clearance = float(point_segments_distance(p, self.segments)[0])
        if clearance < robot_radius_m:
            raise WorldError(
                f"start ({self.start.x:.3f}, {self.start.y:.3f}) is {clearance:.3f} m from a wall;"
                f" the robot needs {robot_radius_m:.3f} m"
            )

    @functools.cached_property
    def wall_arcs(self) -> WallArcs:
        """Where each segment lies along its chain of connected walls (computed once)."""
        return chain_walls(self.segments)

    @property
    def width_m(self) -> float:
        return self.bounds[2] - self.bounds[0]

    @property
    def height_m(self) -> float:
        return self.bounds[3] - self.bounds[1]


class PolygonWorld(World):
    """Free space = inside ``boundary`` and outside every polygon of ``obstacles``."""

    def __init__(
        self,
        name: str,
        boundary: list[tuple[float, float]] | np.ndarray,
        obstacles: list[list[tuple[float, float]]] | list[np.ndarray],
        start: StartPose,
        source: str = "",
    ) -> None:
        outer = _polygon(boundary, "boundary")
        holes = [_polygon(o, f"obstacle {i}") for i, o in enumerate(obstacles)]
        free = outer.difference(unary_union(holes)) if holes else outer
        free = shapely.make_valid(free)
        polys = _polygons_of(free)
        if not polys:
            raise WorldError("the obstacles cover the whole boundary: no free space is left")
        self.free_region = MultiPolygon(polys) if len(polys) > 1 else polys[0]
        self.boundary = np.asarray(outer.exterior.coords, dtype=float)[:-1]
        self.obstacles = [np.asarray(h.exterior.coords, dtype=float)[:-1] for h in holes]
        shapely.prepare(self.free_region)
        segments, corners, convex = _ring_geometry(polys)
        minx, miny, maxx, maxy = outer.bounds
        super().__init__(
            name=name,
            start=start,
            source=source,
            segments=segments,
            corners=corners,
            corner_convex=convex,
            bounds=(float(minx), float(miny), float(maxx), float(maxy)),
            free_area_m2=float(self.free_region.area),
        )

    def is_free(self, points: np.ndarray) -> np.ndarray:
        pts = np.asarray(points, dtype=float).reshape(-1, 2)
        return shapely.contains_xy(self.free_region, pts[:, 0], pts[:, 1])


class GridWorld(World):
    """An occupancy grid: ``occupied[row, col]``, row 0 at the bottom (``origin`` y).

    ``origin`` is the world position of the lower-left corner of cell (0, 0), as in ROS
    map_server (whose images have row 0 at the top: loaders flip them before building this).
    Cells outside the grid count as occupied. The walls are the cells' boundary straightened
    within about a cell (``sim_backend.grid_walls``); collisions use the cells.
    """

    def __init__(
        self,
        name: str,
        occupied: np.ndarray,
        resolution_m: float,
        origin: tuple[float, float],
        start: StartPose,
        source: str = "",
    ) -> None:
        occ = np.asarray(occupied, dtype=bool)
        if occ.ndim != 2 or occ.size == 0:
            raise WorldError("the occupancy grid must be a non-empty 2-D array")
        if not (math.isfinite(resolution_m) and resolution_m > 0):
            raise WorldError(f"resolution must be a positive number of metres, not {resolution_m}")
        if occ.all():
            raise WorldError("every cell is occupied: no free space")
        self.occupied = occ
        self.resolution_m = float(resolution_m)
        self.origin = (float(origin[0]), float(origin[1]))
        segments, corners, convex = grid_walls(
            occ, self.resolution_m, self.origin, wall_tolerance(self.resolution_m)
        )
        rows, cols = occ.shape
        ox, oy = self.origin
        super().__init__(
            name=name,
            start=start,
            source=source,
            segments=segments,
            corners=corners,
            corner_convex=convex,
            bounds=(ox, oy, ox + cols * self.resolution_m, oy + rows * self.resolution_m),
            free_area_m2=float((~occ).sum()) * self.resolution_m**2,
        )

    def is_free(self, points: np.ndarray) -> np.ndarray:
        pts = np.asarray(points, dtype=float).reshape(-1, 2)
        col = np.floor((pts[:, 0] - self.origin[0]) / self.resolution_m).astype(np.int64)
        row = np.floor((pts[:, 1] - self.origin[1]) / self.resolution_m).astype(np.int64)
        rows, cols = self.occupied.shape
        inside = (row >= 0) & (row < rows) & (col >= 0) & (col < cols)
        free = np.zeros(len(pts), dtype=bool)
        free[inside] = ~self.occupied[row[inside], col[inside]]
        return free


@dataclass(frozen=True)
class WallArcs:
    """Segments chained end to end into walls, for distances *along* a wall.

    Segment ``k`` belongs to chain ``chain[k]`` and runs from arc length ``arc0[k]`` to
    ``arc0[k] + length`` (``reversed[k]``: from its second endpoint to its first). A closed
    chain of total length ``closed_length[c]`` wraps around; an open one has ``inf`` there.
    """

    chain: np.ndarray
    arc0: np.ndarray
    reversed: np.ndarray
    closed_length: np.ndarray

    def position(self, seg: np.ndarray, t: np.ndarray, lengths: np.ndarray) -> np.ndarray:
        """Arc length of the point at parameter ``t`` of segments ``seg``."""
        along = np.where(self.reversed[seg], 1.0 - t, t) * lengths[seg]
        return self.arc0[seg] + along

    def along_wall(
        self, chain_a: np.ndarray, s_a: np.ndarray, chain_b: np.ndarray, s_b: np.ndarray
    ) -> np.ndarray:
        """Distance along the wall between two points (inf when on different chains)."""
        d = np.abs(s_a - s_b)
        total = self.closed_length[chain_a]
        d = np.where(np.isfinite(total), np.minimum(d, total - d), d)
        return np.where(chain_a == chain_b, d, np.inf)


def chain_walls(segments: np.ndarray) -> WallArcs:
    """Walk segments that share endpoints into chains (rings where they close)."""
    n = len(segments)
    keys = np.round(segments.reshape(-1, 2) * 1e7).astype(np.int64)
    _, vid = np.unique(keys, axis=0, return_inverse=True)
    vid = vid.reshape(n, 2)
    at: dict[int, list[int]] = {}
    for k in range(n):
        at.setdefault(int(vid[k, 0]), []).append(k)
        at.setdefault(int(vid[k, 1]), []).append(k)
    lengths = np.hypot(segments[:, 2] - segments[:, 0], segments[:, 3] - segments[:, 1])
    chain = np.full(n, -1, dtype=np.int64)
    arc0 = np.zeros(n)
    rev = np.zeros(n, dtype=bool)
    closed: list[float] = []

    def loose(v: int) -> bool:
        return len(at[v]) == 1

    # Walk open chains from a loose end first, so their arc length runs end to end.
    open_starts = [k for k in range(n) if loose(int(vid[k, 0])) or loose(int(vid[k, 1]))]
    for start in open_starts + list(range(n)):
        if chain[start] >= 0:
            continue
        c = len(closed)
        first_v = int(vid[start, 1]) if loose(int(vid[start, 1])) else int(vid[start, 0])
        k, v, s = start, first_v, 0.0
        while True:
            chain[k] = c
            arc0[k] = s
            rev[k] = int(vid[k, 0]) != v
            s += lengths[k]
            v = int(vid[k, 1]) if not rev[k] else int(vid[k, 0])
            nxt = [j for j in at[v] if chain[j] < 0]
            if not nxt:
                ends_where_it_began = v == first_v
                closed.append(s if ends_where_it_began else math.inf)
                break
            k = nxt[0]
    return WallArcs(chain, arc0, rev, np.asarray(closed, dtype=float))


def point_segments_distance(points: np.ndarray, segments: np.ndarray) -> np.ndarray:
    """Distance from each point to the nearest of ``segments`` (brute force, vectorised)."""
    pts = np.asarray(points, dtype=float).reshape(-1, 2)
    if len(segments) == 0:
        return np.full(len(pts), np.inf)
    out = np.empty(len(pts))
    a = segments[:, 0:2]
    d = segments[:, 2:4] - a
    dd = np.maximum((d * d).sum(axis=1), 1e-300)
    chunk = max(1, 2_000_000 // max(1, len(segments)))
    for s in range(0, len(pts), chunk):
        p = pts[s : s + chunk, None, :]
        t = np.clip(((p - a) * d).sum(axis=2) / dd, 0.0, 1.0)
        q = a + t[..., None] * d
        out[s : s + chunk] = np.sqrt(((p - q) ** 2).sum(axis=2)).min(axis=1)
    return out


def _polygon(coords: object, what: str) -> Polygon:
    try:
        arr = np.asarray(coords, dtype=float)
    except (TypeError, ValueError) as exc:
        raise WorldError(f"{what}: vertices must be [x, y] pairs of numbers") from exc
    if arr.ndim != 2 or arr.shape[1] != 2:
        raise WorldError(f"{what}: vertices must be a list of [x, y] pairs")
    if len(arr) < 3:
        raise WorldError(f"{what}: a polygon needs at least 3 vertices, got {len(arr)}")
    if not np.isfinite(arr).all():
        raise WorldError(f"{what}: coordinates must be finite numbers")
    poly = Polygon(arr)
    if not poly.is_valid:
        reason = shapely.is_valid_reason(poly)
        raise WorldError(f"{what}: not a simple polygon ({reason})")
    if poly.area <= 0:
        raise WorldError(f"{what}: the polygon has no area")
    return poly


def _polygons_of(geom: object) -> list[Polygon]:
    if isinstance(geom, Polygon):
        return [geom] if not geom.is_empty else []
    parts = getattr(geom, "geoms", [])
    out: list[Polygon] = []
    for g in parts:
        out.extend(_polygons_of(g))
    return [p for p in out if p.area > 1e-9]


def _ring_geometry(polys: list[Polygon]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Wall segments and classified corners of the rings of free-space polygons."""
    segs: list[np.ndarray] = []
    corners: list[np.ndarray] = []
    convex: list[np.ndarray] = []
    for poly in polys:
        poly = shapely.normalize(poly)  # exterior clockwise, interiors counter-clockwise
        poly = shapely.geometry.polygon.orient(poly, sign=1.0)  # exterior CCW, holes CW
        for ring in [poly.exterior, *poly.interiors]:
            pts = _drop_collinear(np.asarray(ring.coords, dtype=float)[:-1])
            if len(pts) < 3:
                continue
            nxt = np.roll(pts, -1, axis=0)
            segs.append(np.hstack([pts, nxt]))
            prev = np.roll(pts, 1, axis=0)
            e1 = pts - prev
            e2 = nxt - pts
            cross = e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]
            # Free space lies on the left of every ring once oriented: a right turn means
            # free space wraps more than 180 degrees around the vertex.
            corners.append(pts)
            convex.append(cross < 0)
    if not segs:
        raise WorldError("the world has no walls")
    return np.vstack(segs), np.vstack(corners), np.concatenate(convex)


def _drop_collinear(pts: np.ndarray, tol: float = 1e-9) -> np.ndarray:
    keep = []
    n = len(pts)
    for i in range(n):
        a, b, c = pts[i - 1], pts[i], pts[(i + 1) % n]
        cross = (b[0] - a[0]) * (c[1] - b[1]) - (b[1] - a[1]) * (c[0] - b[0])
        if abs(cross) > tol * max(1.0, np.linalg.norm(c - a) ** 2):
            keep.append(b)
    return np.asarray(keep)

"""Ground-truth generalized Voronoi graph (GVG) of a world, as a sonar-ring robot defines it.

This is the reference a sensor-based explorer is scored against, so it follows the paper's
definition (Choset & Nagatani, section III-A) *as the robot can observe it*, not the bare
medial axis.

Definition
----------
Let ``d(x)`` be the distance from a free point ``x`` to the nearest wall point. The GVG is the
set of free points ``x`` that have (at least) two distinct nearest wall points ``p`` and ``q``
(``|x - p| = |x - q| = d(x)``, i.e. ``x`` lies on the medial axis of free space), restricted by
what a ring of 16 sonars (22.5 degrees apart, radius 0.23 m, range 0.15-6.5 m) can resolve:

- *separation*: where ``p`` and ``q`` lie on one bent wall (the path between them along the
  wall is at most ``BENT_WALL_RATIO`` times their distance, or at most ``MIN_DETOUR_M``
  longer: a notch of a rasterised wall), they must subtend an angle of at least
  ``min_separation_deg`` (default 50) at ``x``. The robot finds obstacles as local
  minima of its circular range array (Fig. 4); two points of one wall closer than about two
  sonar spacings in bearing make one minimum, so they are one obstacle. This drops the
  medial-axis spurs into nearly flat (obtuse) wall bends and the ridges between
  neighbouring samples of one wall. Points the wall joins only the long way round (the two
  jambs of a door, the mouth of a niche) are two obstacles at any angle, so the GVG runs
  through doorways into the next room as the paper's robot did (Fig. 14);
- *clearance*: ``min_clearance_m <= d(x) <= max_clearance_m``. Below 0.40 m (ring radius +
  minimum sonar range + margin) the robot can neither measure nor pass; above 6.73 m (ring
  radius + maximum range) it sees no wall at all;
- *accessibility*: only the connected component the robot reaches from the world's start
  pose by moving away from its nearest wall point (the paper's access law) is returned;
  ``other_components`` counts the rest.

Nodes are *meet points* (degree >= 3), *boundary points* (degree 1: the edge reached the
minimum clearance, i.e. ran into a corner where its two obstacles meet, reason
``"clearance"``; or its two nearest points closed below the separation angle, reason
``"separation"``), *horizon* ends (degree 1 where the clearance exceeds the sonar horizon,
reason ``"range"``), and *loop* nodes, one inserted on each cycle that has no other node so
that every cycle is an edge. Edges are polylines from node to node.

Method
------
Every wall segment is sampled densely (endpoints included) and the Voronoi diagram of the
samples is computed. Each finite Voronoi ridge lies on the perpendicular bisector of its two
generating samples, so along the ridge the clearance is ``sqrt(h^2 + u^2)`` and the
subtended angle is ``2 atan(h / |u|)`` (``h`` half the generator distance, ``u`` the offset
from their midpoint): the three restrictions above become intervals of ``u`` and every ridge is
clipped to them exactly, which puts boundary and horizon ends at the precise threshold.
Ridges outside free space are dropped. The kept ridges are chained into polylines; spurs
shorter than ``min_branch_m`` (sampling artefacts) are pruned; junction vertices that
sampling splits one meet point into (joined by paths shorter than a few sample spacings) are
merged, and the meet point is refined to the point equidistant to the walls that generate it
(Gauss-Newton on the exact segment distances). Sampling error on edges is about
``spacing^2 / (8 d)``, well under a millimetre at the defaults; polylines are thinned to
1 mm. Runs in about 2 s for a 50 x 50 m office (1700 m of walls), 0.1 s for a 170 m2 world.

Consequences worth knowing
--------------------------
- Meet points joined by an edge shorter than ``max(3 * spacing, min_branch_m,
  merge_meet_m)`` (``merge_meet_m`` is 0 by default) become one meet point carrying all
  their outer branches, and branches shorter than ``min_branch_m`` do not
  exist: the sonar ring cannot tell either apart.
- A doorway's edge continues into each room, between the two jambs, until it meets the
  room's own GVG at a meet point, however small the angle the jambs subtend there.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import shapely
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import Voronoi, cKDTree

from sim_backend.world import World, point_segments_distance

RING_RADIUS_M = 0.23
SONAR_MIN_RANGE_M = 0.15
SONAR_MAX_RANGE_M = 6.5
DEFAULT_MIN_SEPARATION_DEG = 50.0
DEFAULT_MIN_CLEARANCE_M = 0.40
#: Meet points joined by an edge shorter than this are reported as one. Off by default: a
#: homing robot does tell apart junctions a fraction of a metre apart (measured with
#: ``tslam trace``); set it to the robot's diameter (0.46 m) for a coarser, map-level view
#: of the "points close to each other" of section VII-B.
DEFAULT_MERGE_MEET_M = 0.0
#: Two wall points whose path along the wall is at most this many times the straight line
#: between them lie on one bent wall (a flat bend's ratio is 1 / sin(half its angle) < 1.1).
BENT_WALL_RATIO = 1.5
#: ... or whose path along the wall is at most this much longer than the straight line: a
#: notch or slot a few centimetres deep is no niche to a sonar ring (its 25-degree beam and
#: 0.15 m minimum range see one wall), but a building map made by SLAM has one every few
#: cells of its walls, and each is a 2-3 ratio that otherwise made a spur of the GVG into
#: it: a 30 x 16 m office floor at 5 cm cells, one wall cell in seven flipped, had 445 meet
#: points for the 53 of its clean walls (50 with this rule alone). No built-in or generated world
#: has a detour this short between two sides of a GVG edge.
MIN_DETOUR_M = 0.2
DEFAULT_MAX_CLEARANCE_M = RING_RADIUS_M + SONAR_MAX_RANGE_M
DEFAULT_SAMPLE_SPACING_M = 0.025
DEFAULT_MIN_BRANCH_M = 0.05
DEFAULT_DEPARTURE_DISTANCE_M = 0.4

KINDS = ("meet", "boundary", "horizon", "loop")

# How a polyline end came to be: a Voronoi vertex, or a clip at one of the three limits.
_VERTEX, _MIN_CLEAR, _MAX_CLEAR, _SEPARATION = 0, 1, 2, 3
_REASONS = {_VERTEX: "separation", _MIN_CLEAR: "clearance", _SEPARATION: "separation"}
_SIMPLIFY_TOL_M = 1e-3  # polylines are thinned to this; far below the 1-2 cm scoring tolerance


@dataclass(frozen=True)
class GvgNode:
    """A GVG node. ``departure_angles`` (radians, world frame, in ``[0, 2 pi)``, ascending,
    i.e. counter-clockwise from +x) give the heading of each incident edge measured
    ``departure_distance_m`` along it; ``departure_edges`` are the matching edge ids (a
    self-loop appears twice). They are what a robot homed on the node can compare."""

    id: int
    kind: str
    x: float
    y: float
    clearance_m: float
    degree: int
    reason: str | None = None
    departure_angles: tuple[float, ...] = ()
    departure_edges: tuple[int, ...] = ()

    @property
    def xy(self) -> np.ndarray:
        return np.array([self.x, self.y])


@dataclass(eq=False)
class GvgEdge:
    """A GVG edge: polyline ``points`` (M, 2) running from node ``u`` to node ``v``."""

    id: int
    u: int
    v: int
    points: np.ndarray = field(repr=False)
    length_m: float


@dataclass(eq=False)
class GroundTruthGVG:
    """The accessible GVG component of a world, with the parameters that define it."""

    world_name: str
    nodes: list[GvgNode]
    edges: list[GvgEdge]
    other_components: int
    min_separation_deg: float
    min_clearance_m: float
    max_clearance_m: float
    sample_spacing_m: float
    min_branch_m: float
    departure_distance_m: float
    merge_meet_m: float = DEFAULT_MERGE_MEET_M
    start: tuple[float, float] | None = None
    access_point: tuple[float, float] | None = None
    compute_time_s: float = 0.0
    _index: Any = field(default=None, init=False, repr=False)

    @property
    def meet_points(self) -> list[GvgNode]:
        return [n for n in self.nodes if n.kind == "meet"]

    @property
    def boundary_points(self) -> list[GvgNode]:
        return [n for n in self.nodes if n.kind == "boundary"]

    @property
    def horizon_points(self) -> list[GvgNode]:
        return [n for n in self.nodes if n.kind == "horizon"]

    @property
    def gvg_length_m(self) -> float:
        return float(sum(e.length_m for e in self.edges))

    def node(self, node_id: int) -> GvgNode:
        return self.nodes[node_id]

    def nearest_node(self, x: float, y: float, kind: str | None = None) -> GvgNode | None:
        """The node closest to ``(x, y)``, optionally only among nodes of ``kind``."""
        if kind is not None and kind not in KINDS:
            raise ValueError(f"kind must be one of {KINDS}, not {kind!r}")
        best, best_d = None, math.inf
        for n in self.nodes:
            if kind is not None and n.kind != kind:
                continue
            d = math.hypot(n.x - x, n.y - y)
            if d < best_d:
                best, best_d = n, d
        return best

    def distance_to(self, points: np.ndarray) -> np.ndarray:
        """Distance from each ``(x, y)`` row to the nearest GVG polyline (exact, vectorised).

        A k-d tree over the midpoints of short pieces of the polylines finds candidates; a
        point's nearest piece has its midpoint within ``d + piece/2``, so the candidate set is
        widened until the k-th neighbour is beyond that, which makes the answer exact.
        """
        pts = np.asarray(points, dtype=float).reshape(-1, 2)
        if not self.edges or len(pts) == 0:
            return np.full(len(pts), math.inf)
        if self._index is None:
            self._index = _SegmentIndex([e.points for e in self.edges], piece_m=0.02)
        return self._index.distance(pts)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready summary: positions and lengths in metres rounded to the millimetre."""
        return {
            "world": self.world_name,
            "parameters": {
                "min_separation_deg": self.min_separation_deg,
                "min_clearance_m": self.min_clearance_m,
                "max_clearance_m": self.max_clearance_m,
                "sample_spacing_m": self.sample_spacing_m,
                "min_branch_m": self.min_branch_m,
                "merge_meet_m": self.merge_meet_m,
                "departure_distance_m": self.departure_distance_m,
            },
            "start": None if self.start is None else [round(c, 3) for c in self.start],
            "access_point": (
                None if self.access_point is None else [round(c, 3) for c in self.access_point]
            ),
            "gvg_length_m": round(self.gvg_length_m, 3),
            "other_components": self.other_components,
            "nodes": [
                {
                    "id": n.id,
                    "kind": n.kind,
                    "x": round(n.x, 3),
                    "y": round(n.y, 3),
                    "clearance_m": round(n.clearance_m, 3),
                    "degree": n.degree,
                    "reason": n.reason,
                    "departure_angles_rad": [round(a, 4) for a in n.departure_angles],
                    "departure_edges": list(n.departure_edges),
                }
                for n in self.nodes
            ],
            "edges": [
                {
                    "id": e.id,
                    "u": e.u,
                    "v": e.v,
                    "length_m": round(e.length_m, 3),
                    "points": np.round(e.points, 3).tolist(),
                }
                for e in self.edges
            ],
        }


def compute_gvg(
    world: World,
    *,
    min_separation_deg: float = DEFAULT_MIN_SEPARATION_DEG,
    min_clearance_m: float = DEFAULT_MIN_CLEARANCE_M,
    max_clearance_m: float = DEFAULT_MAX_CLEARANCE_M,
    sample_spacing_m: float = DEFAULT_SAMPLE_SPACING_M,
    min_branch_m: float = DEFAULT_MIN_BRANCH_M,
    departure_distance_m: float = DEFAULT_DEPARTURE_DISTANCE_M,
    merge_meet_m: float = DEFAULT_MERGE_MEET_M,
) -> GroundTruthGVG:
    """The ground-truth GVG of ``world`` (see the module docstring for the definition)."""
    if not 0.0 < min_separation_deg < 180.0:
        raise ValueError("min_separation_deg must lie strictly between 0 and 180")
    if not 0.0 <= min_clearance_m < max_clearance_m:
        raise ValueError("need 0 <= min_clearance_m < max_clearance_m")
    if not sample_spacing_m > 0.0:
        raise ValueError("sample_spacing_m must be positive")
    if min_branch_m < 0.0 or departure_distance_m <= 0.0 or merge_meet_m < 0.0:
        raise ValueError("min_branch_m and merge_meet_m must be >= 0 and departure_distance_m > 0")
    t_start = time.perf_counter()
    builder = _Builder(
        world,
        tan_half_sep=math.tan(math.radians(min_separation_deg) / 2.0),
        cmin=float(min_clearance_m),
        cmax=float(max_clearance_m),
        spacing=float(sample_spacing_m),
        min_branch=float(min_branch_m),
        merge_meet=float(merge_meet_m),
    )
    nodes, edges, others, access = builder.run(float(departure_distance_m))
    return GroundTruthGVG(
        world_name=world.name,
        nodes=nodes,
        edges=edges,
        other_components=others,
        min_separation_deg=float(min_separation_deg),
        min_clearance_m=float(min_clearance_m),
        max_clearance_m=float(max_clearance_m),
        sample_spacing_m=float(sample_spacing_m),
        min_branch_m=float(min_branch_m),
        departure_distance_m=float(departure_distance_m),
        merge_meet_m=float(merge_meet_m),
        start=(float(world.start.x), float(world.start.y)),
        access_point=access,
        compute_time_s=time.perf_counter() - t_start,
    )


# ----------------------------------------------------------------------------------------
# Construction


@dataclass(eq=False)
class _Chain:
    """A polyline between two node keys of the working graph (``a == b`` for a loop)."""

    a: int
    b: int
    pts: np.ndarray
    length: float
    alive: bool = True


@dataclass
class _Node:
    pos: np.ndarray
    code: int
    voronoi: tuple[int, ...] = ()  # Voronoi vertex labels it stands for (junctions only)
    clearance: float | None = None


class _Builder:
    """One GVG computation; keeps the shared arrays so the steps stay small functions."""

    def __init__(
        self,
        world: World,
        *,
        tan_half_sep: float,
        cmin: float,
        cmax: float,
        spacing: float,
        min_branch: float,
        merge_meet: float = 0.0,
    ) -> None:
        self.world = world
        self.tan_half = tan_half_sep
        self.cmin, self.cmax = cmin, cmax
        self.spacing = spacing
        self.min_branch = min_branch
        # Junctions that sampling splits are joined by ridges of about one spacing; real meet
        # points this close are one place to a sonar ring anyway.
        self.merge_len = max(3.0 * spacing, min_branch, merge_meet)
        self.segs = np.asarray(world.segments, dtype=float).reshape(-1, 4)
        self.origin = self.segs[:, 0:2].mean(axis=0)
        self.nodes: dict[int, _Node] = {}
        self.chains: list[_Chain] = []

    # -- pipeline ------------------------------------------------------------------------

    def run(
        self, departure_m: float
    ) -> tuple[list[GvgNode], list[GvgEdge], int, tuple[float, float] | None]:
        self._sample()
        pieces = self._clip_ridges()
        self._chain_pieces(*pieces)
        self._prune_and_splice()
        self._merge_junctions()
        self._prune_and_splice()
        comps = self._components()
        access = self._access_point()
        if not comps:
            return [], [], 0, access
        keep = self._pick_component(comps, access)
        others = len(comps) - 1
        nodes, edges = self._finalise(comps[keep], departure_m)
        return nodes, edges, others, access

    # -- sampling and Voronoi ------------------------------------------------------------

    def _sample(self) -> None:
        segs = self.segs
        a = segs[:, 0:2] - self.origin
        d = segs[:, 2:4] - segs[:, 0:2]
        length = np.hypot(d[:, 0], d[:, 1])
        n = np.maximum(1, np.ceil(length / self.spacing - 1e-9)).astype(np.int64)
        counts = n + 1
        seg_of = np.repeat(np.arange(len(segs)), counts)
        first = np.repeat(np.cumsum(counts) - counts, counts)
        k = np.arange(int(counts.sum())) - first
        t = k / n[seg_of]
        raw = a[seg_of] + t[:, None] * d[seg_of]
        # Shared endpoints would be duplicate Voronoi sites: snap to 0.1 um and deduplicate.
        grid = np.round(raw * 1e7).astype(np.int64)
        grid -= grid.min(axis=0)
        span = int(grid[:, 1].max()) + 1
        if int(grid[:, 0].max()) < (2**62) // span:  # one int64 key per row: a fast 1-D unique
            key = grid[:, 0] * span + grid[:, 1]
            _, first_idx, inverse = np.unique(key, return_index=True, return_inverse=True)
        else:
            _, first_idx, inverse = np.unique(grid, axis=0, return_index=True, return_inverse=True)
        inverse = inverse.reshape(-1)
        self.samples = raw[first_idx]
        self.sample_seg = seg_of[first_idx]
        arcs = self.world.wall_arcs
        self.arcs = arcs
        self.sample_chain = arcs.chain[self.sample_seg]
        self.sample_arc = arcs.position(self.sample_seg, t[first_idx], length)
        # Every segment each sample lies on (two at a corner), for refining meet points.
        n_segs = np.int64(len(segs))
        pairs = np.unique(inverse.astype(np.int64) * n_segs + seg_of)
        self.sample_segs_ptr = np.searchsorted(pairs // n_segs, np.arange(len(self.samples) + 1))
        self.sample_segs = pairs % n_segs
        self.sample_tree = cKDTree(self.samples)

    def _clip_ridges(self) -> tuple[np.ndarray, ...]:
        """Clip every finite ridge to the allowed interval(s) of its bisector parameter."""
        # Collinear wall samples on the convex hull make flat Delaunay facets whose Voronoi
        # vertices Qhull puts far away on an arbitrary side, sending ridges through free
        # space. A distant ring of sites (no three collinear) owns the hull instead; being
        # farther from any free point than every wall, it changes nothing inside.
        n_s = len(self.samples)
        lo, hi = self.samples.min(axis=0), self.samples.max(axis=0)
        diag = float(np.hypot(*(hi - lo)))
        radius = 2.0 * diag + 10.0 * self.spacing + 1.0
        ang = np.linspace(0.0, 2.0 * math.pi, 64, endpoint=False)
        ring = 0.5 * (lo + hi) + radius * np.column_stack([np.cos(ang), np.sin(ang)])
        vor = Voronoi(np.vstack([self.samples, ring]))
        rv_all = np.asarray(vor.ridge_vertices, dtype=np.int64).reshape(-1, 2)
        rp_all = np.asarray(vor.ridge_points, dtype=np.int64).reshape(-1, 2)
        walls_only = (rp_all < n_s).all(axis=1)
        rv_all, rp_all = rv_all[walls_only], rp_all[walls_only]
        self._vertex_generators(rv_all, rp_all, len(vor.vertices))
        finite = (rv_all >= 0).all(axis=1)
        rv, rp = rv_all[finite], rp_all[finite]
        V = vor.vertices
        P, Q = self.samples[rp[:, 0]], self.samples[rp[:, 1]]
        mid = 0.5 * (P + Q)
        dq = Q - P
        dist_pq = np.hypot(dq[:, 0], dq[:, 1])
        h = 0.5 * dist_pq
        e = np.column_stack([-dq[:, 1], dq[:, 0]]) / dist_pq[:, None]
        ua = ((V[rv[:, 0]] - mid) * e).sum(axis=1)
        ub = ((V[rv[:, 1]] - mid) * e).sum(axis=1)
        flip = ua > ub
        v_lo = np.where(flip, rv[:, 1], rv[:, 0])
        v_hi = np.where(flip, rv[:, 0], rv[:, 1])
        u_lo, u_hi = np.minimum(ua, ub), np.maximum(ua, ub)
        # |u| >= a: clearance >= cmin; |u| <= b: clearance <= cmax; |u| <= g: separation.
        a = np.sqrt(np.maximum(self.cmin**2 - h**2, 0.0))
        b = np.where(h <= self.cmax, np.sqrt(np.maximum(self.cmax**2 - h**2, 0.0)), -1.0)
        # The separation rule is for one bent wall seen as one obstacle; two wall points that
        # the wall joins only the long way round (door jambs, a niche's mouth) stay two.
        gp, gq = rp[:, 0], rp[:, 1]
        along = self.arcs.along_wall(
            self.sample_chain[gp], self.sample_arc[gp], self.sample_chain[gq], self.sample_arc[gq]
        )
        bent = (along <= BENT_WALL_RATIO * dist_pq) | (along - dist_pq <= MIN_DETOUR_M)
        g = np.where(bent, h / self.tan_half, np.inf)
        top = np.minimum(b, g)
        top_code = np.where(b <= g, _MAX_CLEAR, _SEPARATION)
        cand = np.nonzero((top >= a) & (top >= 0.0))[0]

        los, his, lcs, hcs, idx = [], [], [], [], []
        whole = cand[a[cand] == 0.0]
        split = cand[a[cand] > 0.0]
        # Wide ridges (h >= cmin): one interval [-top, top].
        lo = np.maximum(u_lo[whole], -top[whole])
        hi = np.minimum(u_hi[whole], top[whole])
        los.append(lo)
        his.append(hi)
        lcs.append(np.where(-top[whole] > u_lo[whole], top_code[whole], -1))
        hcs.append(np.where(top[whole] < u_hi[whole], top_code[whole], -1))
        idx.append(whole)
        # Narrow ridges: [-top, -a] and [a, top].
        for sign in (-1.0, 1.0):
            if sign < 0:
                lo = np.maximum(u_lo[split], -top[split])
                hi = np.minimum(u_hi[split], -a[split])
                lc = np.where(-top[split] > u_lo[split], top_code[split], -1)
                hc = np.where(-a[split] < u_hi[split], _MIN_CLEAR, -1)
            else:
                lo = np.maximum(u_lo[split], a[split])
                hi = np.minimum(u_hi[split], top[split])
                lc = np.where(a[split] > u_lo[split], _MIN_CLEAR, -1)
                hc = np.where(top[split] < u_hi[split], top_code[split], -1)
            los.append(lo)
            his.append(hi)
            lcs.append(lc)
            hcs.append(hc)
            idx.append(split)
        lo, hi = np.concatenate(los), np.concatenate(his)
        lc, hc = np.concatenate(lcs), np.concatenate(hcs)
        r = np.concatenate(idx)
        ok = (hi > lo) | ((hi == lo) & (lc < 0) & (hc < 0))
        lo, hi, lc, hc, r = lo[ok], hi[ok], lc[ok], hc[ok], r[ok]

        p_lo = np.where((lc < 0)[:, None], V[v_lo[r]], mid[r] + lo[:, None] * e[r])
        p_hi = np.where((hc < 0)[:, None], V[v_hi[r]], mid[r] + hi[:, None] * e[r])
        # Clearance along a kept piece is >= cmin > 0, so it cannot cross a wall: one
        # membership test per piece tells free space from the inside of obstacles.
        free = self.world.is_free(0.5 * (p_lo + p_hi) + self.origin)
        # Safety net against numerically broken ridges: a ridge point has no site nearer
        # than its two generators.
        mid = 0.5 * (p_lo + p_hi)
        d_gen = np.hypot(*(mid - self.samples[rp[r, 0]]).T)
        d_near, _ = self.sample_tree.query(mid)
        free &= d_near >= d_gen - 1e-6
        return (
            p_lo[free],
            p_hi[free],
            v_lo[r[free]],
            v_hi[r[free]],
            lc[free],
            hc[free],
            len(V),
        )

    def _vertex_generators(self, rv: np.ndarray, rp: np.ndarray, n_vertices: int) -> None:
        """CSR map Voronoi vertex -> the samples equidistant to it (from all its ridges)."""
        v = np.concatenate([rv[:, 0], rv[:, 0], rv[:, 1], rv[:, 1]])
        s = np.concatenate([rp[:, 0], rp[:, 1], rp[:, 0], rp[:, 1]])
        ok = v >= 0
        width = np.int64(len(self.samples))
        key = np.unique(v[ok] * width + s[ok])
        self.vgen_ptr = np.searchsorted(key // width, np.arange(n_vertices + 1))
        self.vgen = key % width

    # -- chaining ------------------------------------------------------------------------

    def _chain_pieces(
        self,
        p_lo: np.ndarray,
        p_hi: np.ndarray,
        v_lo: np.ndarray,
        v_hi: np.ndarray,
        lc: np.ndarray,
        hc: np.ndarray,
        n_vor: int,
    ) -> None:
        """Turn the kept ridge pieces into polylines between vertices of degree != 2."""
        m = len(p_lo)
        if m == 0:
            return
        # Degenerate (co-circular) sites give coincident Voronoi vertices joined by
        # zero-length ridges: merge them first.
        seglen = np.hypot(*(p_hi - p_lo).T)
        tiny = (lc < 0) & (hc < 0) & (seglen < 1e-9)
        graph = coo_matrix(
            (np.ones(int(tiny.sum())), (v_lo[tiny], v_hi[tiny])), shape=(n_vor, n_vor)
        )
        _, label = connected_components(graph, directed=False)
        self.vor_label_members = _group_indices(label)
        keep = ~tiny
        p_lo, p_hi, lc, hc = p_lo[keep], p_hi[keep], lc[keep], hc[keep]
        id_lo = label[v_lo[keep]]
        id_hi = label[v_hi[keep]]
        m = len(p_lo)
        n_lab = int(label.max()) + 1
        # Clipped ends are new vertices of their own.
        id_lo = np.where(lc < 0, id_lo, n_lab + np.arange(m))
        id_hi = np.where(hc < 0, id_hi, n_lab + m + np.arange(m))
        ids = np.concatenate([id_lo, id_hi])
        uniq, inv = np.unique(ids, return_inverse=True)
        ea, eb = inv[:m], inv[m:]
        n = len(uniq)
        coords = np.empty((n, 2))
        coords[ea] = p_lo
        coords[eb] = p_hi
        coords += self.origin
        code = np.full(n, _VERTEX, dtype=np.int64)
        code[ea] = np.maximum(lc, _VERTEX)
        code[eb] = np.maximum(hc, _VERTEX)
        vor_of = np.where(uniq < n_lab, uniq, -1)

        paths, loops = _walk_chains(n, ea, eb)
        for path in paths + loops:
            for end in (path[0], path[-1]):
                if end not in self.nodes:
                    vl = int(vor_of[end])
                    self.nodes[end] = _Node(
                        pos=coords[end].copy(),
                        code=int(code[end]),
                        voronoi=() if vl < 0 else (vl,),
                    )
            pts = coords[np.asarray(path)]
            self.chains.append(_Chain(path[0], path[-1], pts, _polyline_length(pts)))

    # -- graph surgery -------------------------------------------------------------------

    def _incidence(self) -> dict[int, list[tuple[int, int]]]:
        inc: dict[int, list[tuple[int, int]]] = {}
        for ci, c in enumerate(self.chains):
            if not c.alive:
                continue
            inc.setdefault(c.a, []).append((ci, 0))
            inc.setdefault(c.b, []).append((ci, 1))
        return inc

    def _prune_and_splice(self) -> None:
        """Drop short spurs and specks, then join chains through degree-2 nodes."""
        while True:
            inc = self._incidence()
            deg = {k: len(v) for k, v in inc.items()}
            removed = False
            for c in self.chains:
                if not c.alive or c.length >= self.min_branch:
                    continue
                da, db = deg[c.a], deg[c.b]
                if c.a == c.b:
                    c.alive = False  # a speck of a loop, or a tiny loop on a junction
                    removed = True
                elif da == 1 and db == 1:
                    c.alive = False
                    removed = True
                elif da == 1 and db >= 3:
                    c.alive = False
                    self.nodes[c.b].code = self.nodes[c.a].code
                    removed = True
                elif db == 1 and da >= 3:
                    c.alive = False
                    self.nodes[c.a].code = self.nodes[c.b].code
                    removed = True
            self._splice()
            if not removed:
                break
        self.chains = [c for c in self.chains if c.alive]

    def _splice(self) -> None:
        inc = self._incidence()
        for node in list(inc):
            ends = inc.get(node, [])
            if len(ends) != 2:
                continue
            (c1, e1), (c2, e2) = ends
            if c1 == c2:
                continue  # a loop through this node only: it stays as the loop's node
            ch1, ch2 = self.chains[c1], self.chains[c2]
            p1 = ch1.pts if e1 == 1 else ch1.pts[::-1]  # ends at node
            p2 = ch2.pts if e2 == 0 else ch2.pts[::-1]  # starts at node
            far1 = ch1.a if e1 == 1 else ch1.b
            far2 = ch2.b if e2 == 0 else ch2.a
            new = _Chain(far1, far2, np.vstack([p1, p2[1:]]), ch1.length + ch2.length)
            ch1.alive = ch2.alive = False
            self.chains.append(new)
            ni = len(self.chains) - 1
            del inc[node]
            for far, old, end in ((far1, c1, 0), (far2, c2, 1)):
                lst = inc[far]
                for k, (ci, _) in enumerate(lst):
                    if ci == old:
                        lst[k] = (ni, end)
                        break

    def _merge_junctions(self) -> None:
        """Fuse junction clusters into one meet point each and place it exactly."""
        inc = self._incidence()
        deg = {k: len(v) for k, v in inc.items()}
        junctions = [k for k, d in deg.items() if d >= 3]
        if not junctions:
            return
        parent = {k: k for k in junctions}

        def find(k: int) -> int:
            while parent[k] != k:
                parent[k] = parent[parent[k]]
                k = parent[k]
            return k

        for c in self.chains:
            if (
                c.alive
                and c.a != c.b
                and c.length < self.merge_len
                and deg[c.a] >= 3
                and deg[c.b] >= 3
            ):
                ra, rb = find(c.a), find(c.b)
                if ra != rb:
                    parent[ra] = rb
        clusters: dict[int, list[int]] = {}
        for k in junctions:
            clusters.setdefault(find(k), []).append(k)
        next_key = max(self.nodes) + 1
        for members in clusters.values():
            mset = set(members)
            pos, clearance = self._place_meet(members)
            key = members[0] if len(members) == 1 else next_key
            if len(members) > 1:
                next_key += 1
                vor = tuple(v for k in members for v in self.nodes[k].voronoi)
                self.nodes[key] = _Node(pos=pos, code=_VERTEX, voronoi=vor)
            self.nodes[key].pos = pos
            self.nodes[key].clearance = clearance
            for c in self.chains:
                if not c.alive or (c.a not in mset and c.b not in mset):
                    continue
                if c.a in mset and c.b in mset and c.length < self.merge_len:
                    c.alive = False
                    continue
                if c.a in mset:
                    c.a = key
                    c.pts = _with_end(c.pts, pos, at_start=True)
                if c.b in mset:
                    c.b = key
                    c.pts = _with_end(c.pts, pos, at_start=False)
                c.length = _polyline_length(c.pts)
        self.chains = [c for c in self.chains if c.alive]

    def _place_meet(self, members: list[int]) -> tuple[np.ndarray, float]:
        """The point equidistant to the walls generating a junction cluster.

        Gauss-Newton on ``d_f(x) - r = 0`` over the exact distances to every wall segment
        that generates a cluster vertex; the answer is trusted only if it is equidistant,
        stays near the cluster and no other wall is closer. Otherwise the cluster vertex
        nearest the cluster centre is used (off by at most about a sample spacing).
        """
        cand = np.array([self.nodes[k].pos for k in members])
        centre = cand.mean(axis=0)
        fallback = cand[int(np.argmin(np.hypot(*(cand - centre).T)))]
        labels = [v for k in members for v in self.nodes[k].voronoi]
        vverts = [int(x) for lab in labels for x in self.vor_label_members[lab]]
        gens = (
            np.unique(
                np.concatenate([self.vgen[self.vgen_ptr[v] : self.vgen_ptr[v + 1]] for v in vverts])
            )
            if vverts
            else np.zeros(0, dtype=np.int64)
        )
        seg_ids = (
            np.unique(
                np.concatenate(
                    [
                        self.sample_segs[self.sample_segs_ptr[s] : self.sample_segs_ptr[s + 1]]
                        for s in gens
                    ]
                )
            )
            if len(gens)
            else np.zeros(0, dtype=np.int64)
        )
        spread = float(np.hypot(*(cand - centre).T).max()) if len(cand) > 1 else 0.0
        max_shift = spread + 2.0 * self.spacing
        feats = self.segs[seg_ids]
        # A generator can sit on a wall that is a few millimetres farther than the true
        # nearest ones (a neighbouring sample of a merged cluster, the far side of a corner):
        # drop the worst-fitting wall until the rest are equidistant.
        while len(feats) >= 3:
            sol = _equidistant_point(fallback, feats)
            if sol is None:
                break
            x, r, res = sol
            if np.abs(res).max() <= 1e-4:
                if math.hypot(*(x - fallback)) <= max_shift and bool(
                    self.world.is_free(x[None, :])[0]
                ):
                    clear = float(self._clearance(x[None, :])[0])
                    if clear >= r - 1e-4:
                        return x, clear
                break
            feats = np.delete(feats, int(np.argmax(np.abs(res))), axis=0)
        return fallback.copy(), float(self._clearance(fallback[None, :])[0])

    # -- components and access -----------------------------------------------------------

    def _components(self) -> list[list[int]]:
        """Chain indices grouped by connected component."""
        parent: dict[int, int] = {}

        def find(k: int) -> int:
            parent.setdefault(k, k)
            while parent[k] != k:
                parent[k] = parent[parent[k]]
                k = parent[k]
            return k

        for c in self.chains:
            ra, rb = find(c.a), find(c.b)
            if ra != rb:
                parent[ra] = rb
        comps: dict[int, list[int]] = {}
        for ci, c in enumerate(self.chains):
            comps.setdefault(find(c.a), []).append(ci)
        return list(comps.values())

    def _access_point(self) -> tuple[float, float] | None:
        """Where the paper's access law (move away from the nearest wall) meets the medial
        axis: the first point on that ray whose nearest wall point is no longer the start's.
        """
        s = np.array([self.world.start.x, self.world.start.y], dtype=float)
        if not bool(self.world.is_free(s[None, :])[0]):
            return None
        p = _nearest_wall_point(s, self.segs)
        d0 = float(np.hypot(*(s - p)))
        if d0 < 1e-9:
            return (float(s[0]), float(s[1]))
        u = (s - p) / d0
        step = self.spacing / 4.0
        t = np.arange(0.0, 2.0 * self.cmax + step, step)
        ray = s + t[:, None] * u
        free = self.world.is_free(ray)
        if not free.all():
            t, ray = t[: int(np.argmin(free))], ray[: int(np.argmin(free))]
        if len(t) == 0:
            return (float(s[0]), float(s[1]))
        d_near, _ = self.sample_tree.query(ray - self.origin)
        past = np.nonzero((d0 + t) - d_near > 0.5 * self.spacing)[0]
        hit = ray[past[0]] if len(past) else ray[-1]
        return (float(hit[0]), float(hit[1]))

    def _pick_component(self, comps: list[list[int]], access: tuple[float, float] | None) -> int:
        target = (
            np.array(access)
            if access is not None
            else np.array([self.world.start.x, self.world.start.y])
        )
        best, best_d = 0, math.inf
        for i, comp in enumerate(comps):
            d = min(
                float(_polyline_distance(target[None, :], self.chains[ci].pts)[0]) for ci in comp
            )
            if d < best_d:
                best, best_d = i, d
        return best

    # -- output --------------------------------------------------------------------------

    def _finalise(self, comp: list[int], departure_m: float) -> tuple[list[GvgNode], list[GvgEdge]]:
        chains = [self.chains[ci] for ci in comp]
        ends: dict[int, list[tuple[int, int]]] = {}
        for i, c in enumerate(chains):
            ends.setdefault(c.a, []).append((i, 0))
            ends.setdefault(c.b, []).append((i, 1))

        def kind_of(key: int) -> tuple[str, str | None]:
            d = len(ends[key])
            if d >= 3:
                return "meet", None
            if d == 2:
                return "loop", None
            code = self.nodes[key].code
            if code == _MAX_CLEAR:
                return "horizon", "range"
            return "boundary", _REASONS[code]

        rank = {k: i for i, k in enumerate(KINDS)}
        keys = sorted(
            ends,
            key=lambda k: (
                rank[kind_of(k)[0]],
                round(float(self.nodes[k].pos[0]), 6),
                round(float(self.nodes[k].pos[1]), 6),
            ),
        )
        node_id = {k: i for i, k in enumerate(keys)}
        need = [k for k in keys if self.nodes[k].clearance is None]
        if need:
            cl = self._clearance(np.array([self.nodes[k].pos for k in need]))
            for k, c in zip(need, cl, strict=True):
                self.nodes[k].clearance = float(c)

        # Edges: thinned polylines, oriented from the lower to the higher node id.
        lines = []
        for c in chains:
            pts = c.pts
            u, v = node_id[c.a], node_id[c.b]
            if u > v:
                pts, u, v = pts[::-1], v, u
            pts = pts.copy()
            pts[0] = self.nodes[keys[u]].pos
            pts[-1] = self.nodes[keys[v]].pos
            lines.append((u, v, _thin(pts)))
        lines.sort(key=lambda t: (t[0], t[1], _polyline_length(t[2])))
        edges = [
            GvgEdge(id=i, u=u, v=v, points=pts, length_m=_polyline_length(pts))
            for i, (u, v, pts) in enumerate(lines)
        ]
        departures: dict[int, list[tuple[float, int]]] = {i: [] for i in range(len(keys))}
        for e in edges:
            departures[e.u].append((_departure_angle(e.points, departure_m), e.id))
            departures[e.v].append((_departure_angle(e.points[::-1], departure_m), e.id))
        nodes = []
        for i, k in enumerate(keys):
            kind, reason = kind_of(k)
            dep = sorted(departures[i])
            nd = self.nodes[k]
            nodes.append(
                GvgNode(
                    id=i,
                    kind=kind,
                    x=float(nd.pos[0]),
                    y=float(nd.pos[1]),
                    clearance_m=float(nd.clearance if nd.clearance is not None else math.nan),
                    degree=len(ends[k]),
                    reason=reason,
                    departure_angles=tuple(a for a, _ in dep),
                    departure_edges=tuple(e for _, e in dep),
                )
            )
        return nodes, edges

    # -- geometry helpers ----------------------------------------------------------------

    def _clearance(self, pts: np.ndarray) -> np.ndarray:
        """Exact distance to the walls: candidate segments come from the nearest samples."""
        pts = np.asarray(pts, dtype=float).reshape(-1, 2)
        k = min(12, len(self.samples))
        _, idx = self.sample_tree.query(pts - self.origin, k=k)
        idx = np.asarray(idx).reshape(len(pts), k)
        segs = self.segs[self.sample_seg[idx]]  # (P, k, 4)
        return _point_segment_dist(pts[:, None, :], segs).min(axis=1)


# ----------------------------------------------------------------------------------------
# Small helpers


def _walk_chains(n: int, ea: np.ndarray, eb: np.ndarray) -> tuple[list[list[int]], list[list[int]]]:
    """Vertex paths between vertices of degree != 2, and the pure cycles left over."""
    m = len(ea)
    deg = np.bincount(ea, minlength=n) + np.bincount(eb, minlength=n)
    src = np.concatenate([ea, eb])
    dst = np.concatenate([eb, ea])
    eid = np.concatenate([np.arange(m), np.arange(m)])
    order = np.argsort(src, kind="stable")
    nbr = dst[order].tolist()
    ned = eid[order].tolist()
    ptr = np.concatenate([[0], np.cumsum(deg)]).tolist()
    degl = deg.tolist()
    used = bytearray(m)

    def walk(start: int, k: int) -> list[int]:
        path = [start]
        used[ned[k]] = 1
        cur = nbr[k]
        while degl[cur] == 2 and cur != start:
            path.append(cur)
            j = ptr[cur]
            if used[ned[j]]:
                j += 1
                if used[ned[j]]:
                    break
            used[ned[j]] = 1
            cur = nbr[j]
        path.append(cur)
        return path

    paths = []
    for s in np.nonzero(deg != 2)[0].tolist():
        for k in range(ptr[s], ptr[s + 1]):
            if not used[ned[k]]:
                paths.append(walk(s, k))
    loops = []
    for e in range(m):
        if not used[e]:
            s = int(ea[e])
            k = next(j for j in range(ptr[s], ptr[s + 1]) if ned[j] == e)
            loops.append(walk(s, k))
    return paths, loops


def _group_indices(label: np.ndarray) -> list[np.ndarray]:
    order = np.argsort(label, kind="stable")
    bounds = np.searchsorted(label[order], np.arange(int(label.max()) + 2))
    return [order[bounds[i] : bounds[i + 1]] for i in range(len(bounds) - 1)]


def _polyline_length(pts: np.ndarray) -> float:
    if len(pts) < 2:
        return 0.0
    d = np.diff(pts, axis=0)
    return float(np.hypot(d[:, 0], d[:, 1]).sum())


def _with_end(pts: np.ndarray, pos: np.ndarray, *, at_start: bool) -> np.ndarray:
    end = pts[0] if at_start else pts[-1]
    if float(np.hypot(*(end - pos))) < 1e-9:
        return pts
    return np.vstack([pos, pts]) if at_start else np.vstack([pts, pos])


def _thin(pts: np.ndarray) -> np.ndarray:
    """Douglas-Peucker thinning; a closed loop is thinned as two halves so it stays open."""
    if len(pts) <= 2:
        return pts
    if float(np.hypot(*(pts[0] - pts[-1]))) < 1e-9:
        h = len(pts) // 2
        first, second = _thin(pts[: h + 1]), _thin(pts[h:])
        return np.vstack([first, second[1:]])
    line = shapely.simplify(shapely.LineString(pts), _SIMPLIFY_TOL_M, preserve_topology=False)
    out = np.asarray(line.coords, dtype=float)
    return out if len(out) >= 2 else pts[[0, -1]]


def _departure_angle(pts: np.ndarray, dist: float) -> float:
    """Heading from ``pts[0]`` to the polyline point ``dist`` along it (or its far end)."""
    d = np.diff(pts, axis=0)
    seg = np.hypot(d[:, 0], d[:, 1])
    cum = np.concatenate([[0.0], np.cumsum(seg)])
    if cum[-1] <= dist:
        target = pts[-1]
        if float(np.hypot(*(target - pts[0]))) < 1e-9:  # a loop: use its middle
            target = pts[len(pts) // 2]
    else:
        i = int(np.searchsorted(cum, dist, side="right")) - 1
        f = (dist - cum[i]) / seg[i] if seg[i] > 0 else 0.0
        target = pts[i] + f * d[i]
    ang = math.atan2(target[1] - pts[0][1], target[0] - pts[0][0])
    ang %= 2.0 * math.pi
    return 0.0 if ang >= 2.0 * math.pi else ang  # -1e-17 % 2 pi rounds up to 2 pi


def _point_segment_dist(p: np.ndarray, segs: np.ndarray) -> np.ndarray:
    """Broadcast distance from points ``p`` (..., 2) to segments ``segs`` (..., 4)."""
    a = segs[..., 0:2]
    d = segs[..., 2:4] - a
    dd = np.maximum((d * d).sum(axis=-1), 1e-300)
    t = np.clip(((p - a) * d).sum(axis=-1) / dd, 0.0, 1.0)
    q = a + t[..., None] * d
    return np.hypot(p[..., 0] - q[..., 0], p[..., 1] - q[..., 1])


def _nearest_wall_point(p: np.ndarray, segs: np.ndarray) -> np.ndarray:
    a = segs[:, 0:2]
    d = segs[:, 2:4] - a
    dd = np.maximum((d * d).sum(axis=1), 1e-300)
    t = np.clip(((p - a) * d).sum(axis=1) / dd, 0.0, 1.0)
    q = a + t[:, None] * d
    return q[int(np.argmin(np.hypot(*(q - p).T)))]


def _equidistant_point(
    x0: np.ndarray, segs: np.ndarray
) -> tuple[np.ndarray, float, np.ndarray] | None:
    """Least squares (Gauss-Newton) for ``x, r`` with ``dist(x, seg_f) = r`` for every ``f``.

    Returns the point, the radius and the residuals, or None if it degenerates.
    """
    a = segs[:, 0:2]
    d = segs[:, 2:4] - a
    dd = np.maximum((d * d).sum(axis=1), 1e-300)

    def distances(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        t = np.clip(((x - a) * d).sum(axis=1) / dd, 0.0, 1.0)
        diff = x - (a + t[:, None] * d)
        return diff, np.hypot(diff[:, 0], diff[:, 1])

    z = np.array([x0[0], x0[1], 0.0])
    diff, dist = distances(z[:2])
    z[2] = dist.mean()
    for _ in range(30):
        if (dist < 1e-12).any():
            return None
        res = dist - z[2]
        J = np.column_stack([diff / dist[:, None], -np.ones(len(dist))])
        step = np.linalg.lstsq(J, -res, rcond=None)[0]
        z = z + step
        diff, dist = distances(z[:2])
        if float(np.abs(step).max()) < 1e-11:
            break
    if not np.isfinite(z).all():
        return None
    return z[:2].copy(), float(z[2]), dist - z[2]


def _polyline_distance(points: np.ndarray, poly: np.ndarray) -> np.ndarray:
    """Brute-force distance from points to one polyline (small inputs only)."""
    if len(poly) == 1:
        return np.hypot(*(points - poly[0]).T)
    return point_segments_distance(points, np.hstack([poly[:-1], poly[1:]]))


class _SegmentIndex:
    """Exact nearest-polyline distance through a k-d tree over short polyline pieces."""

    def __init__(self, polylines: list[np.ndarray], piece_m: float) -> None:
        starts, ends = [], []
        for pts in polylines:
            if len(pts) < 2:
                starts.append(pts[:1])
                ends.append(pts[:1])
                continue
            d = np.diff(pts, axis=0)
            seg = np.hypot(d[:, 0], d[:, 1])
            n = np.maximum(1, np.ceil(seg / piece_m)).astype(np.int64)
            rep = np.repeat(np.arange(len(seg)), n)
            k = np.arange(int(n.sum())) - np.repeat(np.cumsum(n) - n, n)
            f0 = (k / n[rep])[:, None]
            f1 = ((k + 1) / n[rep])[:, None]
            starts.append(pts[rep] + f0 * d[rep])
            ends.append(pts[rep] + f1 * d[rep])
        self.a = np.vstack(starts)
        self.b = np.vstack(ends)
        self.half = 0.5 * float(np.hypot(*(self.b - self.a).T).max())
        self.tree = cKDTree(0.5 * (self.a + self.b))

    def distance(self, pts: np.ndarray) -> np.ndarray:
        out = np.full(len(pts), math.inf)
        todo = np.arange(len(pts))
        k = 8
        n_pieces = len(self.a)
        while len(todo):
            kk = min(k, n_pieces)
            dmid, idx = self.tree.query(pts[todo], k=kk)
            dmid = np.asarray(dmid).reshape(len(todo), kk)
            idx = np.asarray(idx).reshape(len(todo), kk)
            segs = np.concatenate([self.a[idx], self.b[idx]], axis=-1)
            best = _point_segment_dist(pts[todo][:, None, :], segs).min(axis=1)
            out[todo] = best
            if kk == n_pieces:
                break
            # Complete unless an unseen piece could still be closer than ``best``.
            unsure = dmid[:, -1] < best + self.half
            todo = todo[unsure]
            k *= 4
        return out

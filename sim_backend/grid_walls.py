"""The walls of an occupancy grid as straight lines, the way the building has them.

A map built by SLAM (the ROS map_server maps users bring) draws a straight wall as a ragged
line of cells, and a wall at an angle as a staircase. Taken cell edge by cell edge, such a wall
is a field of little facets and corners to the simulated sonar: each step's facets face the
grid's axes, not the wall's normal, every step is a corner that echoes, and the ground truth
grows a spur of the GVG into every notch. The building has a flat wall there. So the boundary
between free and occupied cells is walked into closed rings, and each ring is simplified
(Douglas-Peucker) within a tolerance of about a cell: ragged edges and staircases become the
straight walls they stand for, while anything larger than the tolerance (a pillar, a door jamb,
a step of a coarse grid) keeps its shape. Collisions still use the cells.
"""

from __future__ import annotations

import math

import numpy as np
import shapely

#: Cells up to this size are a SLAM map's noise and straightened; a coarser grid's steps are
#: taken as its shape (a test world of 0.5 m cells means its staircase).
MAX_TOLERANCE_M = 0.05
#: A vertex of a straightened ring turning less than this is no corner to the sonar: a
#: straightened wall keeps a slight kink here and there, which is no corner reflector.
MIN_CORNER_TURN_RAD = math.radians(15.0)

# Lattice steps, in (row, col): east, north, west, south.
_STEPS = ((0, 1), (1, 0), (0, -1), (-1, 0))


def wall_tolerance(resolution_m: float) -> float:
    """How far a wall may move when the grid's rings are straightened."""
    return min(resolution_m, MAX_TOLERANCE_M)


def grid_walls(
    occ: np.ndarray, res: float, origin: tuple[float, float], tolerance_m: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Wall segments (x0, y0, x1, y1), corners and whether each is convex, of the boundary
    between free and occupied cells of ``occ`` (row 0 at ``origin``'s y; outside the grid is
    occupied), each ring straightened within ``tolerance_m``."""
    ox, oy = origin
    segs: list[np.ndarray] = []
    corners: list[np.ndarray] = []
    convex: list[np.ndarray] = []
    for ring in boundary_rings(occ):
        pts = np.column_stack([ox + ring[:, 1] * res, oy + ring[:, 0] * res]).astype(float)
        pts = _straightened(pts, tolerance_m)
        nxt = np.roll(pts, -1, axis=0)
        segs.append(np.hstack([pts, nxt]))
        prev = np.roll(pts, 1, axis=0)
        e1, e2 = pts - prev, nxt - pts
        cross = e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]
        dot = (e1 * e2).sum(axis=1)
        turn = np.abs(np.arctan2(cross, dot))
        sharp = turn >= MIN_CORNER_TURN_RAD
        corners.append(pts[sharp])
        # Free space is on the left of every ring: a right turn wraps free space around.
        convex.append(cross[sharp] < 0)
    return (
        np.vstack(segs) if segs else np.zeros((0, 4)),
        np.vstack(corners) if corners else np.zeros((0, 2)),
        np.concatenate(convex) if convex else np.zeros(0, dtype=bool),
    )


def boundary_rings(occ: np.ndarray) -> list[np.ndarray]:
    """The free/occupied boundary as closed rings of lattice vertices (row, col), free space
    on the left, with only the vertices where the ring turns. Where two occupied cells touch
    only at a corner the ring goes on round both, so diagonal neighbours are one obstacle,
    as they are to the sonar."""
    rows, cols = occ.shape
    padded = np.ones((rows + 2, cols + 2), dtype=bool)
    padded[1:-1, 1:-1] = occ
    # out[v]: the directed unit edges leaving lattice vertex v (row, col), free on the left.
    out: dict[tuple[int, int], list[int]] = {}
    below, above = padded[:-1, 1:-1], padded[1:, 1:-1]  # cells under/over vertex row i
    for i, j in zip(*np.nonzero(below != above), strict=True):
        # Going east the left is north: east if the cell above is free.
        if not above[i, j]:
            out.setdefault((int(i), int(j)), []).append(0)
        else:
            out.setdefault((int(i), int(j) + 1), []).append(2)
    left, right = padded[1:-1, :-1], padded[1:-1, 1:]  # cells west/east of vertex col j
    for i, j in zip(*np.nonzero(left != right), strict=True):
        # Going north the left is west: north if the cell to the west is free.
        if not left[i, j]:
            out.setdefault((int(i), int(j)), []).append(1)
        else:
            out.setdefault((int(i) + 1, int(j)), []).append(3)
    rings = []
    while out:
        # Not from a pinch, where the way in (unknown at the start) picks the way out.
        start = next((v for v, dirs in out.items() if len(dirs) == 1), next(iter(out)))
        v, d, first = start, -1, -1
        ring = []
        while dirs := out.get(v):
            # At a pinch, turning left (free space is on the left) goes on round the occupied
            # cell diagonal to the one just passed.
            k = 0 if len(dirs) == 1 else max(range(len(dirs)), key=lambda k: (dirs[k] - d + 2) % 4)
            nd = dirs.pop(k)
            first = nd if first < 0 else first
            if not dirs:
                del out[v]
            if nd != d:
                ring.append(v)
            d = nd
            v = (v[0] + _STEPS[d][0], v[1] + _STEPS[d][1])
        # Every vertex kept turns, but maybe the one the walk began at, mid-edge.
        if len(ring) > 1 and d == first:
            ring = ring[1:]
        rings.append(np.asarray(ring, dtype=np.int64).reshape(-1, 2))
    return [r for r in rings if len(r) >= 4]


def _straightened(pts: np.ndarray, tolerance_m: float) -> np.ndarray:
    """The ring simplified within ``tolerance_m``, or as it is if that would collapse it."""
    if tolerance_m <= 0.0:
        return pts
    ring = shapely.LinearRing(pts)
    simple = shapely.simplify(ring, tolerance_m, preserve_topology=True)
    coords = np.asarray(simple.coords, dtype=float)[:-1]
    if len(coords) < 3 or shapely.Polygon(coords).area <= 0.25 * shapely.Polygon(pts).area:
        return pts
    return coords

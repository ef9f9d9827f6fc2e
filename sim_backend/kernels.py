"""Compiled geometry kernels for the simulator's inner loops (numba, cached on disk).

They work on a *subset* of a world's segments (indices near the robot) so their cost does not
grow with the size of the building.
"""

from __future__ import annotations

import math

import numba
import numpy as np

_EPS = 1e-9


@numba.njit(cache=True)
def min_distance(px: float, py: float, segs: np.ndarray, idx: np.ndarray) -> float:
    """Distance from ``(px, py)`` to the nearest segment among ``segs[idx]``."""
    best = np.inf
    for k in range(idx.shape[0]):
        s = idx[k]
        x1 = segs[s, 0]
        y1 = segs[s, 1]
        dx = segs[s, 2] - x1
        dy = segs[s, 3] - y1
        l2 = dx * dx + dy * dy
        t = 0.0
        if l2 > 0.0:
            t = ((px - x1) * dx + (py - y1) * dy) / l2
            t = min(1.0, max(0.0, t))
        qx = x1 + t * dx - px
        qy = y1 + t * dy - py
        d = qx * qx + qy * qy
        if d < best:
            best = d
    return math.sqrt(best)


@numba.njit(cache=True)
def _visible(
    ox: float, oy: float, px: float, py: float, segs: np.ndarray, idx: np.ndarray, skip: int
) -> bool:
    """True when no segment (other than ``skip``) crosses the open line from o to p."""
    rx = px - ox
    ry = py - oy
    for k in range(idx.shape[0]):
        s = idx[k]
        if s == skip:
            continue
        x1 = segs[s, 0]
        y1 = segs[s, 1]
        sx = segs[s, 2] - x1
        sy = segs[s, 3] - y1
        den = rx * sy - ry * sx
        if abs(den) < 1e-15:
            continue
        qx = x1 - ox
        qy = y1 - oy
        t = (qx * sy - qy * sx) / den  # along o -> p
        u = (qx * ry - qy * rx) / den  # along the segment
        if 1e-9 < t < 1.0 - 1e-7 and -1e-12 <= u <= 1.0 + 1e-12:
            return False
    return True


@numba.njit(cache=True)
def sonar_echo(
    ox: float,
    oy: float,
    yaw: float,
    half_beam: float,
    max_range: float,
    convex_range: float,
    side_lobe: float,
    side_range: float,
    segs: np.ndarray,
    seg_idx: np.ndarray,
    corners: np.ndarray,
    convex: np.ndarray,
    corner_idx: np.ndarray,
) -> tuple[float, float]:
    """Ranges of the first echo a transducer at ``(ox, oy)`` pointing at ``yaw`` hears in its
    main lobe and in its side lobes (inf: none). Whether a side-lobe echo is heard is for the
    caller to draw.

    The model (a specular ultrasonic cone):

    - a flat wall echoes only from the foot of the perpendicular from the transducer, and only
      when that foot lies on the wall and inside the beam (normal incidence within the cone);
      walls seen at grazing incidence are silent;
    - a room corner (two walls meeting with free space inside) echoes from its vertex whenever
      the vertex is inside the beam, like a corner reflector;
    - an obstacle's convex edge diffracts a weak echo, heard only up to ``convex_range``;
    - the side lobes (up to ``side_lobe`` off the axis) return a flat wall at normal
      incidence too, but weakly: only up to ``side_range``;
    - an echo counts only if nothing blocks the straight path to it.
    """
    ax = math.cos(yaw)
    ay = math.sin(yaw)
    cos_half = math.cos(half_beam)
    cos_side = math.cos(side_lobe)
    best = np.inf
    side = np.inf
    for k in range(seg_idx.shape[0]):
        s = seg_idx[k]
        x1 = segs[s, 0]
        y1 = segs[s, 1]
        dx = segs[s, 2] - x1
        dy = segs[s, 3] - y1
        l2 = dx * dx + dy * dy
        if l2 <= 0.0:
            continue
        t = ((ox - x1) * dx + (oy - y1) * dy) / l2
        if t < 0.0 or t > 1.0:
            continue
        fx = x1 + t * dx
        fy = y1 + t * dy
        vx = fx - ox
        vy = fy - oy
        d = math.sqrt(vx * vx + vy * vy)
        if d < _EPS or d > max_range:
            continue
        along = vx * ax + vy * ay
        if along >= cos_half * d:
            if d < best and _visible(ox, oy, fx, fy, segs, seg_idx, s):
                best = d
        elif (
            along >= cos_side * d
            and d <= side_range
            and d < side
            and _visible(ox, oy, fx, fy, segs, seg_idx, s)
        ):
            side = d
    for k in range(corner_idx.shape[0]):
        c = corner_idx[k]
        vx = corners[c, 0] - ox
        vy = corners[c, 1] - oy
        d = math.sqrt(vx * vx + vy * vy)
        limit = convex_range if convex[c] else max_range
        if d < _EPS or d >= best or d > limit:
            continue
        if vx * ax + vy * ay < cos_half * d:
            continue
        if _visible(ox, oy, corners[c, 0], corners[c, 1], segs, seg_idx, -1):
            best = d
    return best, side


def segments_near(segs: np.ndarray, x: float, y: float, radius: float) -> np.ndarray:
    """Indices of the segments that come within ``radius`` of ``(x, y)``."""
    if len(segs) == 0:
        return np.zeros(0, dtype=np.int64)
    a = segs[:, 0:2]
    d = segs[:, 2:4] - a
    dd = np.maximum((d * d).sum(axis=1), 1e-300)
    p = np.array([x, y])
    t = np.clip(((p - a) * d).sum(axis=1) / dd, 0.0, 1.0)
    q = a + t[:, None] * d
    dist2 = ((q - p) ** 2).sum(axis=1)
    return np.nonzero(dist2 <= radius * radius)[0].astype(np.int64)


def points_near(pts: np.ndarray, x: float, y: float, radius: float) -> np.ndarray:
    """Indices of the points within ``radius`` of ``(x, y)``."""
    if len(pts) == 0:
        return np.zeros(0, dtype=np.int64)
    d2 = (pts[:, 0] - x) ** 2 + (pts[:, 1] - y) ** 2
    return np.nonzero(d2 <= radius * radius)[0].astype(np.int64)

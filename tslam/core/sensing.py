"""From a sonar ring to obstacles: distances and their gradients (section III-A, Fig. 4).

The ring fires one transducer at a time, so a scan holds readings up to a second old taken
from other poses. Each echo is therefore carried into the robot's *current* frame with the
dead reckoning between its stamp and now: over a second, odometry is good to millimetres
(its drift matters over tens of metres, not here).

Each echo is placed on the transducer's axis (the paper's centreline model, Fig. 3), and,
since a wall returns sound only at near-normal incidence, taken as a wall square to that axis:
its distance and normal then stay exact however far the robot has moved along it since the
transducer fired (a point model would tilt every gradient by the motion). The ring is then
read as a circular array of distances from the robot's centre, and obstacles are its
local minima, by the rules of Fig. 4:

- a reading that is not a local minimum is not a separate obstacle;
- a run of equal adjacent readings (within ``plateau_m``) that is lower than the readings on
  both sides is one obstacle, lying between them;
- a transducer with no echo reads "infinitely far": it never is a minimum, and it separates
  the minima on either side;
- an isolated short reading far below its own previous reading and both neighbours (a
  multipath or crosstalk spike) is held back until the transducer confirms it;
- two minima closer than ``merge_rad`` in bearing are one obstacle (a wall heard by two
  transducers with a silent one between them), as in the ground truth's separation rule;
- two minima up to ``bend_merge_rad`` apart are one obstacle if they could be one bent wall:
  about equally far, and nothing between them deeper than ``bend_ratio`` times that (the
  vertex of a flat concave bend), as the sweep joins them (``tslam.core.sweep``).

Each obstacle ``i`` carries ``d_i`` (metres from the robot's centre) and ``grad_i``, the unit
vector pointing away from its closest point, both in the robot frame.
"""

from __future__ import annotations

import functools
import math
from collections import deque
from dataclasses import dataclass

import numpy as np

from hal.types import Odometry, SonarScan


@dataclass(frozen=True)
class Obstacle:
    """One local minimum of the ring: distance and gradient in the robot frame."""

    distance_m: float
    x_m: float  # closest point, robot frame
    y_m: float
    gx: float  # unit gradient: away from the closest point
    gy: float
    bearing_rad: float


class PoseHistory:
    """Recent dead-reckoned poses, to carry old readings into the current frame."""

    def __init__(self, horizon_s: float = 3.0) -> None:
        self.horizon_s = horizon_s
        self._t: deque[float] = deque()
        self._pose: deque[tuple[float, float, float]] = deque()
        # The arrays ``at`` interpolates in, built once per pose added: it is asked two or
        # three times a control step (the corner kept in a gap needs the poses twice).
        self._arrays: tuple[np.ndarray, np.ndarray] | None = None

    def add(self, odo: Odometry) -> None:
        self._arrays = None
        if self._t and odo.stamp_s <= self._t[-1]:
            if odo.stamp_s == self._t[-1]:
                self._pose[-1] = (odo.x_m, odo.y_m, odo.heading_rad)
            return
        self._t.append(odo.stamp_s)
        self._pose.append((odo.x_m, odo.y_m, odo.heading_rad))
        while len(self._t) > 2 and self._t[1] < odo.stamp_s - self.horizon_s:
            self._t.popleft()
            self._pose.popleft()

    def at(self, stamps: np.ndarray) -> np.ndarray:
        """Poses ``(n, 3)`` at ``stamps``, linearly interpolated; clamped at the ends."""
        if not self._t:
            raise ValueError("no odometry yet")
        if self._arrays is None:
            p = np.array(self._pose, dtype=float).reshape(-1, 3)
            # As np.unwrap, which changes nothing (and costs 20 us) unless a step crosses pi.
            if not np.all(np.abs(np.diff(p[:, 2])) < math.pi):
                p[:, 2] = np.unwrap(p[:, 2])
            self._arrays = (np.fromiter(self._t, float, len(self._t)), p)
        t, p = self._arrays
        out = np.empty((len(stamps), 3))
        for k in range(3):
            out[:, k] = np.interp(stamps, t, p[:, k])
        return out

    def latest(self) -> tuple[float, float, float]:
        return self._pose[-1]


@dataclass
class SensingParams:
    plateau_m: float = 0.02
    spike_m: float = 0.4
    merge_rad: float = math.radians(50.0)
    # A 45-degree cut corner read 56 degrees apart on the ring (each face answers the
    # transducer nearest its normal, +/-11 degrees): with no meet point there for the sweep to
    # confirm, the ring kept proposing one, homing swung the trace law's tangent round and the
    # robot went back down the edge it had come up (fig12 seed 6, drift paper). Joining such
    # faces up to 60 degrees, as the sweep does, fixed that run, but over the 30 paper traces
    # it left more junctions unhomed (51 passes of 337 against 45 of 324) for fewer misread
    # degrees (2 traces against 5), and the 36-run paper bench completed as many runs
    # (9, other seeds). Off (0) until it shows better on the whole.
    bend_merge_rad: float = 0.0
    bend_ratio: float = 1.25
    # In a second reading of the minima (``RingSensor.apart``), two closer than ``merge_rad``
    # stay two if an echo between them is this many times deeper than the farther: a
    # doorway's jambs with the view through it between them, two obstacles at any angle, as
    # the ground truth and the sweep have them. The tracer turns to it only where its pair is
    # lost (TracerParams.doorway_pairs): in every reading, over the 60 traces the edge-length
    # target was met in 45 against 51 (stop 41), and used for meet points, fig13's
    # duplicates rose (README, stop 41). 1.8, not 1.4: a right-angled corner's vertex is 1.41
    # times as far as its walls, and at 1.4 the robot traced two faces of fig15's corners as a
    # doorway's jambs into the corner, backing off and tracing in again (232 contacts in one
    # run). 0: one always.
    view_ratio: float = 1.8
    hold_s: float = 1.5  # keep an echo through one silent firing of its transducer
    # A convex corner answers only while it lies in some transducer's beam, and the beams,
    # fanned from a ring 0.23 m off the centre, leave gaps between them that widen as the
    # corner comes closer (1.5 m off, at one heading in seven no transducer hears it). So
    # when a transducer's echo gives way to a farther one, its last echo is kept, as the
    # point it was, for up to ``gap_hold_s`` while it lies in no transducer's beam that has
    # fired since and heard past it (0: not kept). fig13 seed 9: the robot walked to 0.27 m
    # of a cabinet's corner the ring had heard and lost, and homed onto three walls 1.7 m off.
    # On since stop 38 (the switch ``gap_hold`` before): with TracerParams.home_spread_m, on
    # the three benches 48 runs of 130 complete against 39, 739 wrong edges against 1158, 222
    # contacts against 1131, no false merge (README, stop 38).
    gap_hold_s: float = 3.0
    gap_jump_m: float = 0.3  # the new echo this much farther than the last one
    gap_tol_m: float = 0.15  # a beam that heard this far past the point: it is not there
    # A neighbour's echo held back as a spike confirms nothing (False: it still does, as
    # before; TracerParams says why this and the tracer's switches are off by default).
    held_no_support: bool = False


class RingSensor:
    """Turns scans into obstacles; keeps the little state that spike rejection needs."""

    def __init__(self, params: SensingParams | None = None) -> None:
        self.p = params or SensingParams()
        self.history = PoseHistory(max(3.0, self.p.gap_hold_s + 1.0))
        self._last_stamp: np.ndarray | None = None
        self._prev_dist: np.ndarray | None = None
        self._held: np.ndarray | None = None
        self._keep: tuple[np.ndarray, ...] | None = None
        self._gap: np.ndarray | None = None  # kept echoes held because they lie in a gap
        self.points: np.ndarray | None = None  # the last update's echo points (robot frame)
        # The last update's minima and distances, for ``apart`` (asked for now and then).
        self._found: tuple[list[tuple[Obstacle, int, int]], np.ndarray] | None = None
        self._merged = 0  # how many obstacles the last update reported
        # ``apart``'s answer for the last update, once asked (the tracer asks up to three
        # times a cycle).
        self._apart: list[Obstacle] | None = None
        self._apart_asked = False

    def update(self, scan: SonarScan, odo: Odometry) -> list[Obstacle]:
        """Obstacles seen from the pose ``odo``, nearest first."""
        self.history.add(odo)
        pts = self.echo_points(scan)
        self.points = pts
        p = self.p
        self._found = found = _minima(pts, p.plateau_m)
        self._apart_asked = False
        if found is None:
            self._merged = 0
            return []
        minima, d = found
        obs = _merge_split_walls(minima, d, p.merge_rad, p.bend_merge_rad, p.bend_ratio)
        self._merged = len(obs)
        return obs

    def apart(self) -> list[Obstacle] | None:
        """The last update's obstacles with two close minima kept apart where the ring sees
        between them (``SensingParams.view_ratio``: a doorway's jambs), nearest first; None
        if that keeps none apart."""
        if not self._apart_asked:
            self._apart_asked = True
            self._apart = self._kept_apart()
        return self._apart

    def _kept_apart(self) -> list[Obstacle] | None:
        p = self.p
        if self._found is None or p.view_ratio <= 0.0:
            return None
        minima, d = self._found
        obs = _merge_split_walls(
            minima, d, p.merge_rad, p.bend_merge_rad, p.bend_ratio, p.view_ratio
        )
        return obs if len(obs) > self._merged else None

    def _held_echoes(self, scan: SonarScan) -> tuple[np.ndarray, ...]:
        """The latest echo of each transducer, kept through a silent firing for ``hold_s``:
        a missed echo (a dropout) should not make a wall vanish for a whole second; and
        through a farther echo for ``gap_hold_s`` while it lies in a gap between the beams."""
        fresh_echo = ~np.isnan(scan.ranges_m)
        n = len(scan)
        if self._keep is None or len(self._keep[0]) != n:
            self._keep = tuple(
                a.copy() for a in (scan.ranges_m, scan.x_m, scan.y_m, scan.yaw_rad, scan.stamps_s)
            )
            self._gap = np.zeros(n, dtype=bool)
        assert self._gap is not None
        r, x, y, yaw, t = self._keep
        gap = self._in_gap(scan) if self.p.gap_hold_s > 0.0 else np.zeros(n, dtype=bool)
        take = fresh_echo & ~gap
        for dst, src in zip(
            (r, x, y, yaw, t),
            (scan.ranges_m, scan.x_m, scan.y_m, scan.yaw_rad, scan.stamps_s),
            strict=True,
        ):
            dst[take] = src[take]
        self._gap = gap
        stale = scan.stamps_s - t > np.where(gap, self.p.gap_hold_s, self.p.hold_s)
        r[stale] = np.nan
        t[stale] = scan.stamps_s[stale]
        self._gap &= ~stale
        return r, x, y, yaw, t

    def _in_gap(self, scan: SonarScan) -> np.ndarray:
        """Which transducers' kept echoes stay although the transducer has fired since: an
        echo given way to one ``gap_jump_m`` farther (or already held so), younger than
        ``gap_hold_s``, whose point no beam fired since covers and heard past."""
        assert self._keep is not None and self._gap is not None
        r, x, y, yaw, t = self._keep
        fired = scan.stamps_s > t
        new = np.where(np.isnan(scan.ranges_m), np.inf, scan.ranges_m)
        cand = np.isfinite(r) & (scan.stamps_s - t <= self.p.gap_hold_s)
        cand &= self._gap | (fired & (new > r + self.p.gap_jump_m))
        if not cand.any():
            return cand
        # The kept points in the odometry frame, then in each transducer's frame as it fired.
        wx, wy = _in_odometry(r[cand], x[cand], y[cand], yaw[cand], self.history.at(t[cand]))
        now = self.history.at(scan.stamps_s)
        cj, sj = np.cos(now[:, 2]), np.sin(now[:, 2])
        dx = wx[:, None] - now[None, :, 0]
        dy = wy[:, None] - now[None, :, 1]
        px = cj[None, :] * dx + sj[None, :] * dy - scan.x_m[None, :]
        py = -sj[None, :] * dx + cj[None, :] * dy - scan.y_m[None, :]
        dist = np.hypot(px, py)
        along = px * np.cos(scan.yaw_rad)[None, :] + py * np.sin(scan.yaw_rad)[None, :]
        covers = (along >= math.cos(scan.half_beam_rad) * dist) & (dist <= scan.max_range_m)
        after = scan.stamps_s[None, :] > t[cand][:, None]
        past = new[None, :] > dist + self.p.gap_tol_m
        out = np.zeros_like(cand)
        out[np.flatnonzero(cand)] = ~(covers & after & past).any(axis=1)
        return out

    def echo_points(self, scan: SonarScan) -> np.ndarray:
        """Echo points ``(n, 2)`` in the current robot frame, NaN where there is none."""
        n = len(scan)
        r, sx, sy, syaw, stamps = self._held_echoes(scan)
        poses = self.history.at(stamps)
        x0, y0, th0 = self.history.latest()
        wx, wy = _in_odometry(r, sx, sy, syaw, poses)
        c0, s0 = math.cos(th0), math.sin(th0)
        dx, dy = wx - x0, wy - y0
        px, py = c0 * dx + s0 * dy, -s0 * dx + c0 * dy
        # The echo came back at normal incidence: model it as a wall through the echo point,
        # square to the transducer's axis (as it pointed then). Its distance and normal stay
        # right however far the robot moved along it since.
        axis = syaw + poses[:, 2] - th0
        ux, uy = np.cos(axis), np.sin(axis)
        dist = px * ux + py * uy
        # A corner kept through a gap is the point it was, not a wall square to the beam.
        gap = self._gap
        assert gap is not None
        pts = np.empty((n, 2))
        pts[:, 0] = np.where(gap, px, dist * ux)
        pts[:, 1] = np.where(gap, py, dist * uy)
        if gap.any():
            dist = np.where(gap, np.hypot(px, py), dist)
        fresh = (
            np.ones(n, dtype=bool)
            if self._last_stamp is None or len(self._last_stamp) != n
            else stamps > self._last_stamp
        )
        far = np.where(np.isnan(dist), np.inf, dist)  # no echo: infinitely far
        if self._held is None or len(self._held) != n:
            self._held = np.zeros(n, dtype=bool)
            self._prev_dist = far.copy()
        prev = self._prev_dist
        assert prev is not None
        below = far + self.p.spike_m
        # A neighbour's echo held back as a spike is no support: two outliers side by side
        # would otherwise confirm each other (fig12 through the CAN board: a held 0.43 m lie
        # kept for its 1.5 s let a 0.42 m one beside it through, and the robot turned back
        # mid-corridor at a "boundary point").
        support = np.where(self._held, np.inf, far) if self.p.held_no_support else far
        after, before = _neighbours(n)
        spike = fresh & (below < prev) & (below < support[before]) & (below < support[after])
        # A spike is held once; if the transducer repeats it, it is real: ``prev`` is then the
        # held spike, which a repeat is not far below. A second spike far below the first is
        # held in turn (on a ring that fires fast, two outliers on one transducer a few
        # firings apart do happen, and the second was taken for the first's confirmation).
        self._held = np.where(fresh, spike, self._held)
        self._prev_dist = np.where(fresh, far, prev)
        self._last_stamp = stamps.copy()
        pts[self._held] = np.nan
        return pts


@functools.cache
def _neighbours(n: int) -> tuple[np.ndarray, np.ndarray]:
    """Index arrays of each reading's neighbours on a ring of ``n`` (as ``np.roll``, cheaper)."""
    i = np.arange(n)
    return (i + 1) % n, (i - 1) % n


def _in_odometry(
    r: np.ndarray, x: np.ndarray, y: np.ndarray, yaw: np.ndarray, poses: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Echo points in the odometry frame: each on its transducer's axis (robot frame at
    firing time: ``x``, ``y``, ``yaw``), ``r`` along it, from the pose it fired at."""
    ex = x + r * np.cos(yaw)
    ey = y + r * np.sin(yaw)
    c, s = np.cos(poses[:, 2]), np.sin(poses[:, 2])
    return poses[:, 0] + c * ex - s * ey, poses[:, 1] + s * ex + c * ey


def local_minima(
    pts: np.ndarray,
    plateau_m: float = 0.02,
    merge_rad: float = math.radians(50.0),
    bend_merge_rad: float = 0.0,
    bend_ratio: float = 1.25,
    view_ratio: float = 0.0,
) -> list[Obstacle]:
    """The Fig. 4 rules on a circular array of echo points (robot frame, NaN = no echo);
    ``bend_merge_rad`` 0 joins no bent walls beyond ``merge_rad``; ``view_ratio`` 0 joins
    minima closer than ``merge_rad`` whatever the ring sees between them."""
    found = _minima(pts, plateau_m)
    if found is None:
        return []
    minima, d = found
    return _merge_split_walls(minima, d, merge_rad, bend_merge_rad, bend_ratio, view_ratio)


def _minima(
    pts: np.ndarray, plateau_m: float
) -> tuple[list[tuple[Obstacle, int, int]], np.ndarray] | None:
    """Every local minimum of the ring (with its plateau's first and last index), nearest
    first, and the readings' distances; None if there is no echo at all."""
    n = len(pts)
    d = np.hypot(pts[:, 0], pts[:, 1])
    d = np.where(np.isnan(d), np.inf, d)
    # The ring is 16 readings: plain floats in a Python loop cost a fifth of numpy scalars.
    dl: list[float] = d.tolist()
    if min(dl) == math.inf:
        return None
    out: list[tuple[Obstacle, int, int]] = []  # with the plateau's first and last index
    visited = [False] * n
    for i in range(n):
        di = dl[i]
        if visited[i] or not math.isfinite(di):
            continue
        # Grow the plateau of readings equal to d[i] around i.
        lo, hi = i, i
        while hi - lo + 1 < n and abs(dl[(hi + 1) % n] - di) <= plateau_m:
            hi += 1
        while hi - lo + 1 < n and abs(dl[(lo - 1) % n] - di) <= plateau_m:
            lo -= 1
        idx = [k % n for k in range(lo, hi + 1)]
        for k in idx:
            visited[k] = True
        if len(idx) == n:
            continue  # the same distance all round: no direction to call an obstacle
        level = di if len(idx) == 1 else max([dl[k] for k in idx])
        if dl[(lo - 1) % n] <= level or dl[(hi + 1) % n] <= level:
            continue
        px, py = pts[i].tolist()
        dist = di
        if len(idx) > 1:
            xy = pts[idx].tolist()
            px = sum(p[0] for p in xy) / len(idx)
            py = sum(p[1] for p in xy) / len(idx)
            dist = sum(dl[k] for k in idx) / len(idx)
        norm = math.hypot(px, py)
        if norm < 1e-9:
            continue
        ux, uy = px / norm, py / norm
        ob = Obstacle(dist, ux * dist, uy * dist, -ux, -uy, math.atan2(uy, ux))
        out.append((ob, lo % n, hi % n))
    out.sort(key=lambda t: t[0].distance_m)
    return out, d


def _merge_split_walls(
    minima: list[tuple[Obstacle, int, int]],
    d: np.ndarray,
    merge_rad: float,
    bend_merge_rad: float,
    bend_ratio: float,
    view_ratio: float = 0.0,
) -> list[Obstacle]:
    """A wall heard by two transducers with a silent one between them shows as two minima a
    few tens of degrees apart; the ring cannot resolve obstacles that close in bearing
    (the ground truth's separation rule), so the nearer one stands for both. So does the
    nearer of two faces of one flat bend up to ``bend_merge_rad`` apart."""
    kept: list[tuple[Obstacle, int, int]] = []
    for m in minima:  # nearest first
        o = m[0]
        for k in kept:
            sep = abs((o.bearing_rad - k[0].bearing_rad + math.pi) % (2 * math.pi) - math.pi)
            if sep < merge_rad and view_ratio > 0.0 and _view_between(k, m, d, view_ratio):
                continue
            if sep < merge_rad or (sep < bend_merge_rad and _one_bend(k, m, d, bend_ratio)):
                break
        else:
            kept.append(m)
    return [k[0] for k in kept]


def _view_between(
    a: tuple[Obstacle, int, int], b: tuple[Obstacle, int, int], d: np.ndarray, ratio: float
) -> bool:
    """Whether the ring sees past minima ``a`` and ``b``: an echo between them (the short
    way round) ``ratio`` times deeper than the farther of the two, the view through a doorway
    between its jambs. A bent wall's vertex is never that deep (1.22 times for a bend of 70
    degrees between normals), and a silent transducer between two minima is a wall's echo
    missed, not a view."""
    n = len(d)
    ccw, cw = (b[1] - a[2]) % n, (a[1] - b[2]) % n
    start, steps = (a[2], ccw) if ccw <= cw else (b[2], cw)
    between = d[[(start + k) % n for k in range(1, steps)]]
    far = ratio * max(a[0].distance_m, b[0].distance_m)
    return bool(np.any(np.isfinite(between) & (between > far)))


def _one_bend(
    a: tuple[Obstacle, int, int], b: tuple[Obstacle, int, int], d: np.ndarray, ratio: float
) -> bool:
    """Whether minima ``a`` and ``b`` could be two faces of one concave bend: about equally
    far, and every reading on the short way round between them an echo no deeper than
    ``ratio`` times the farther (no echo, or a deeper one, is a view past the bend)."""
    da, db = a[0].distance_m, b[0].distance_m
    if max(da, db) > ratio * min(da, db):
        return False
    n = len(d)
    ccw, cw = (b[1] - a[2]) % n, (a[1] - b[2]) % n
    start, steps = (a[2], ccw) if ccw <= cw else (b[2], cw)
    between = d[[(start + k) % n for k in range(1, steps)]]
    return bool(np.all(between <= ratio * max(da, db)))

"""A dense look around from a standstill: the turret swept through one sonar spacing.

Sixteen transducers 22.5 degrees apart place a wall's bearing only to within +/-11 degrees:
a flat wall answers only the transducer whose beam holds its normal, wherever that normal
falls in the beam. Two walls 45 degrees apart then show 23 to 68 degrees apart, so whether
the ring resolves them as two obstacles (and a meet point sits between them) would depend
on the robot's heading. At a meet point the robot is standing still anyway, so it turns the
turret slowly through one spacing (the Nomad's turret turns independently of the wheels)
and collects every firing. A flat wall then echoes over the whole +/-12.5 degree span of
axes that contain its normal, at one distance; a convex corner likewise over the span
that contains its bearing. By Fig. 4's rule for equal adjacent readings the obstacle lies in
the middle of that plateau, which is its true direction to a few degrees.

``sweep_minima`` applies the Fig. 4 rules to the dense, irregular circular array: a run of
readings within noise of its lowest one is one obstacle, lying at the run's middle; a run
that borders a lower reading is a slope, not an obstacle; no echo separates runs.

Two runs closer than ``merge_rad`` in bearing are one obstacle only where they could be one
bent wall: every reading between them is no echo (a side lobe or a dropout split the
plateau) or no deeper than ``bend_ratio`` times their distance (the vertex of a flat
concave bend). A deeper view between them some degrees wide, such as a doorway's into the
next room, makes them two obstacles at any angle: the ground truth's bent-wall rule, seen by
sonar. A single deeper reading is an outlier.
"""

from __future__ import annotations

import math

import numpy as np

from hal.types import SonarScan
from tslam.core.sensing import Obstacle

#: The ground truth joins two points of one bent wall closer than 50 degrees; the sweep's
#: bearings are good to about 5 degrees each, so it joins up to 60 lest a 45-degree bend
#: (fig12's cut corner) show as a meet point from some headings.
BENT_WALL_MERGE_RAD = math.radians(60.0)
#: But each face of a concave bend answers only on its own side of the bend, so its plateau
#: is cut short there and its middle lies some degrees away from the bend: fig12's cut
#: corner read 61 degrees apart and was taken for a meet point. With the tracer's
#: ``centred_meet`` the sweep joins up to 70.
WIDE_BEND_MERGE_RAD = math.radians(70.0)
#: The narrowest view past a bend that makes its two faces two obstacles, in readings and in
#: degrees: one outlier between a cut corner's faces made fig12's a meet point, and a fast
#: ring's outliers come several to a degree. A doorway's view between its jambs can be as
#: narrow as 7 degrees (fig14's lab door, 32 degrees of jamb to jamb from the junction beside
#: it, less the 25-degree beam): one reading of a Nomad ring's sweep, 5.6 degrees apart. So a
#: single deeper reading makes the sweep *doubtful*, and the tracer sweeps once more.
MIN_VIEW_READINGS = 2
MIN_VIEW_RAD = math.radians(5.0)
#: ... and, read with ``agree``, the readings of one view lie this close in distance,
#: relatively: they meet the same wall beyond.
VIEW_AGREE_REL = 0.2
#: A doorway onto a room deeper than the sonar's range shows no echo between its jambs, not a
#: deeper one, and its two jambs were one bent wall: the corridor's junction in front of a
#: 1 m door, jambs 59 degrees apart, was swept and rejected twice (a floor of two rooms off a
#: corridor, seed 1), and the room beyond was never explored. With ``silent_view`` so many
#: readings running with no echo, and no reading between the two runs as near as a bend's
#: vertex (a concave corner echoes from its vertex whatever the beam's angle), are a view.
SILENT_VIEW_READINGS = 3
SILENT_VIEW_RAD = math.radians(12.0)
#: Further apart than ``merge_rad``, two runs are still one bent wall up to this angle if
#: the readings between them show a shallow bend's vertex: no deeper than this ratio, which
#: a concave bend of about 55 degrees between normals gives (1 / cos 27.5).
BENT_WALL_MAX_RAD = math.radians(90.0)
SHALLOW_BEND_RATIO = 1.12
#: A wall set back between two nearer obstacles (a recess: fig16's indent seen from the
#: corridor) answers over its normal's whole span, but its side lobes reach the nearer
#: obstacles' plateaus, so its run borders a lower one and reads as a slope; or its run
#: counts and chains to them as one bent wall. A plateau ``RECESS_MIN_RAD`` wide is no
#: slope (a slope rises across it), and with a nearer run within ``RECESS_FRAME_RAD`` beyond
#: each end it is the recess's back wall.
RECESS_MIN_RAD = math.radians(15.0)
RECESS_FRAME_RAD = math.radians(35.0)
#: A sweep of more readings than this is a ring that fires fast (a CAN sonar board's: some 600
#: a turn, where a Nomad ring's 16 transducers fire four times each, twice that when the
#: turret turns twice) ...
DENSE_READINGS = 256
#: ... and is first reduced to this many bearings, each the median of its readings: as dense
#: as a Nomad ring's sweep turned twice.
DENSE_BINS = 128


#: A reading this close to the transducer's minimum range is one it could not measure.
TOUCH_M = 0.01


def at_minimum_range(scan: SonarScan) -> np.ndarray:
    """Which transducers read their minimum range: something nearer than they can measure."""
    return scan.ranges_m <= scan.min_range_m + TOUCH_M


class Sweep:
    """Collects the firings of a standing robot while its turret turns."""

    def __init__(self, start_s: float = -math.inf) -> None:
        self.start_s = start_s  # firings before this were taken on the move
        self._last: np.ndarray | None = None
        self._bearing: list[float] = []
        self._dist: list[float] = []
        # Firings that read the transducer's minimum range: something nearer than it can
        # measure. A convex corner that close answers too few of a sweep's firings to count
        # as an obstacle, but it is there.
        self.touching = 0

    def add(self, scan: SonarScan, heading_rad: np.ndarray | float = 0.0) -> None:
        """Take the firings of ``scan`` not seen before. ``heading_rad``: the body's
        dead-reckoned heading at each firing. The robot stands, but its body may still be
        turning as the sweep begins (homing swings the synchro drive's wheels about, and
        they brake at 30 deg/s^2, some 35 degrees from full rate): a bearing in the body's
        frame would smear each wall over that turn, so bearings are kept in the odometry
        frame and given back relative to the heading ``obstacles`` is asked at."""
        stamps = scan.stamps_s
        new = stamps >= self.start_s
        if self._last is not None and len(self._last) == len(scan):
            new &= stamps > self._last
        self._last = stamps.copy()
        r = np.where(np.isnan(scan.ranges_m), np.inf, scan.ranges_m)
        ex = scan.x_m + np.where(np.isfinite(r), r, 0.0) * np.cos(scan.yaw_rad)
        ey = scan.y_m + np.where(np.isfinite(r), r, 0.0) * np.sin(scan.yaw_rad)
        bearing = scan.yaw_rad + heading_rad
        self.touching += int(np.count_nonzero(new & at_minimum_range(scan)))
        for i in np.flatnonzero(new):
            self._bearing.append(float(bearing[i]))
            self._dist.append(float(math.hypot(ex[i], ey[i])) if math.isfinite(r[i]) else math.inf)

    @property
    def firings_per_transducer(self) -> float:
        """How many times each transducer answered during the sweep (about 4 on a Nomad
        ring at 60 ms a transducer; dozens on a ring that fires all within 100 ms)."""
        return len(self._dist) / len(self._last) if self._last is not None else 0.0

    def obstacles(
        self,
        heading_rad: float = 0.0,
        merge_rad: float = BENT_WALL_MERGE_RAD,
        bridge: bool = False,
        doubts: list[float] | None = None,
        silent: bool = False,
        shallow: bool = False,
        vertex: bool = False,
        recess: bool = False,
        agree: bool = False,
        silent_view: bool = False,
    ) -> list[Obstacle]:
        """The obstacles seen, in the frame of a robot heading ``heading_rad``; the options
        as for ``sweep_minima``."""
        bearing = np.asarray(self._bearing) - heading_rad
        return sweep_minima(
            bearing,
            np.asarray(self._dist),
            merge_rad,
            bridge=bridge,
            doubts=doubts,
            silent=silent,
            shallow=shallow,
            vertex=vertex,
            recess=recess,
            agree=agree,
            silent_view=silent_view,
        )


def sweep_minima(
    bearing_rad: np.ndarray,
    distance_m: np.ndarray,
    merge_rad: float = BENT_WALL_MERGE_RAD,
    tol_m: float = 0.06,
    tol_rel: float = 0.03,
    bend_ratio: float = 1.25,
    min_samples: int = 3,
    min_run_rad: float = math.radians(8.0),
    bridge: bool = False,
    doubts: list[float] | None = None,
    silent: bool = False,
    shallow: bool = False,
    vertex: bool = False,
    recess: bool = False,
    agree: bool = False,
    silent_view: bool = False,
) -> list[Obstacle]:
    """Obstacles of a dense circular array of readings (bearing, distance; inf = no echo).

    A reading within ``tol_m + tol_rel * d`` of a run's lowest reading ``d`` belongs to the
    run (the sonar's noise is about 1 cm + 1 %, so this is some three deviations); runs
    are grown from the lowest reading up. With ``bridge`` a run reaches over one reading off
    its plateau to the next one on it: a dropout, or another transducer's echo from a side
    lobe or the far wall at the same bearing, cuts a wall's run into pieces too short to
    count otherwise, and a junction's third wall goes unseen. With ``silent`` (and without
    ``bridge``) pieces too short to count are joined over readings with no echo between
    them: at fig13's meet point 5, 2 cm off it, dropouts cut two of its three walls into
    pieces of one and two readings, and the sweep rejected the point.

    Two runs joined as one bent wall although a deeper reading lies between them add the
    bearing of that view to ``doubts``: more readings there would tell a stray echo from a
    doorway. With ``shallow`` two runs up to 90 degrees apart are one wall if the readings
    between them show a shallow bend's vertex (``_shallow_bend``). With ``vertex`` two runs
    are not one bent wall if readings between them lie beyond the vertex their two faces
    would make (``_bend_vertex``) and a shallow bend's (``SHALLOW_BEND_RATIO``). With
    ``recess`` a plateau that borders a lower run is still an obstacle if it is wide and
    framed by two nearer obstacles (``_recessed``). With ``agree`` a view between two runs
    is deeper readings that see about as far.

    A sweep of more than ``DENSE_READINGS`` readings (a ring that fires fast) is read as the
    medians of ``DENSE_BINS`` sectors, with ``shallow`` on and ``recess`` and ``agree`` off.
    """
    n = len(bearing_rad)
    if n < 3:
        return []
    order = np.argsort(np.mod(bearing_rad, 2 * math.pi), kind="stable")
    b = np.mod(bearing_rad[order], 2 * math.pi)
    d = distance_m[order]
    dense = n > DENSE_READINGS
    if dense:
        # A ring that fires fast sweeps hundreds of readings, and with them its outliers
        # (0.41 m amid a wall's 1.3 m made the wall two slopes), dropouts (a wall cut into
        # pieces, each too short to count) and noise (the lowest of hundreds of readings some
        # 3.5 deviations low, so readings as far high broke the plateau): at fig12's
        # junctions the sweep lost a wall so on most visits. The beam is 25 degrees wide, so
        # a median every 2.8 degrees loses nothing, and the rules below were made for such a
        # sweep. Two faces with a shallow bend's vertex between them are one wall (fig12's
        # cut corner read 71 degrees apart, a meet point swept for minutes): that holds on
        # readings this clean.
        b, d = _binned(b, d, DENSE_BINS)
        n = len(d)
        shallow = True
        # The recess reading was made on a Nomad ring's sweeps; on these the robot lost
        # fig16's indent more often (at drift paper, 4 ms a firing: seeds 1-8 complete 0
        # times with it, 2 without).
        recess = False
        # A sector's median is no stray already; with ``agree`` on these, fig12 seed 1 at
        # 4 ms a firing, without drift, mapped a fourth meet point.
        agree = False
    claimed = np.full(n, -1)
    # Each reading stands for the sweep's mean spacing: a slow ring's few readings each cover
    # degrees, a fast ring's many a fraction of one.
    fewest = max(min_samples, math.ceil(min_run_rad * n / (2 * math.pi)))
    runs: list[tuple[float, float, int, int]] = []  # distance, mid bearing, lo, hi
    short: list[tuple[int, float]] = []  # runs too short to count: seed reading, limit
    counted: list[int] = []  # the run ids in ``runs``
    for run_id, i in enumerate(np.argsort(d, kind="stable")):
        if not math.isfinite(d[i]):
            break
        if claimed[i] >= 0:
            continue
        limit = d[i] + tol_m + tol_rel * d[i]
        lo, hi, slope = _grow(d, claimed, int(i), limit, bridge, False)
        idx, member = _span(d, lo, hi, limit)
        claimed[idx] = run_id
        if slope or len(idx) == n or len(member) < fewest:
            # A real wall or corner answers over the whole beam: several samples of a sweep,
            # over some 25 degrees of axis. A run of one or two is a stray echo, and so is a
            # side lobe's run on a ring that fires fast: it answers half its firings at
            # random, so its runs hold several samples, but only a few degrees' worth.
            if not slope and len(member) < fewest:
                short.append((int(i), limit))
            continue
        runs.append(_run(b, d, idx, member, lo, hi))
        counted.append(run_id)
    sloped = _sloped(b, d, claimed, counted, tol_m, tol_rel, fewest) if recess else []
    if silent and not bridge and short:
        # A run too short to count may be a wall that dropouts cut into pieces (no echo
        # between readings on one plateau). Only such pieces are joined, after every run
        # that counts on its own has its readings: reaching over a dropout from a piece
        # into a whole run moved that run's middle, and fig12's cut corner read as two
        # walls 62 degrees apart.
        free = np.isin(claimed, [-1] + [int(claimed[i]) for i, _ in short])
        open_ = np.where(free, -1, claimed)
        runs += [r for r, slope in _joined(b, d, open_, short, fewest) if not slope]
    if not runs:
        return []
    # Neighbouring runs on one bent wall join, in chains (a side-lobe fragment, the wall,
    # the next face of the bend); the nearest run of a chain stands for it. A recess's back
    # wall joins neither neighbour: fig16's indent read as one wall round its two corners.
    runs.sort(key=lambda r: r[1])
    if recess:
        flagged = [r for r in runs + sloped if _recessed(r, runs, b, d, tol_m)]
        runs = sorted(set(runs) | set(flagged), key=lambda r: r[1])
        set_back = [r in flagged for r in runs]
    else:
        set_back = [False] * len(runs)
    m = len(runs)
    parent = list(range(m))

    def root(k: int) -> int:
        while parent[k] != k:
            k = parent[k]
        return k

    # Every neighbouring pair, counter-clockwise: with two runs that is both arcs between them.
    for k in range(m if m > 1 else 0):
        if set_back[k] or set_back[(k + 1) % m]:
            continue
        a, c = runs[k], runs[(k + 1) % m]
        one = _one_wall(a, c, d, merge_rad, bend_ratio, shallow, vertex, agree, silent_view)
        if one is not False:
            parent[root((k + 1) % m)] = root(k)
        if one is None and doubts is not None:
            doubts.append(float(a[1] + 0.5 * ((c[1] - a[1]) % (2 * math.pi))))
    best: dict[int, tuple[float, float, int, int]] = {}
    for k, run in enumerate(runs):
        r = root(k)
        if r not in best or run[0] < best[r][0]:
            best[r] = run
    if dense:
        # A wall's side lobes answer half the firings for some 17 degrees either side of its
        # plateau, at its distance: a piece of them, a centimetre nearer by noise, stood for
        # the wall 20 degrees off its normal. The widest run as near as the nearest does.
        nearest = dict(best)
        for k, run in enumerate(runs):
            r = root(k)
            level = nearest[r][0] + tol_m + tol_rel * nearest[r][0]
            if run[0] <= level and _width(run, n) > _width(best[r], n):
                best[r] = run
    out = []
    for dist, mid, _, _ in sorted(best.values()):
        ux, uy = math.cos(mid), math.sin(mid)
        out.append(Obstacle(dist, ux * dist, uy * dist, -ux, -uy, math.atan2(uy, ux)))
    return out


def _width(run: tuple[float, float, int, int], n: int) -> int:
    """How many readings ``run`` spans, of a sweep of ``n``."""
    return (run[3] - run[2]) % n + 1


def _binned(b: np.ndarray, d: np.ndarray, bins: int) -> tuple[np.ndarray, np.ndarray]:
    """Readings in bearing order (``b`` in [0, 2 pi)) reduced to ``bins`` equal sectors, each
    at its middle with the median of its echoes, or no echo where most of its readings have
    none; sectors with no reading are left out."""
    sector = np.minimum((b * bins / (2 * math.pi)).astype(int), bins - 1)
    cut = np.searchsorted(sector, np.arange(bins + 1))
    out_b, out_d = [], []
    for j in range(bins):
        v = d[cut[j] : cut[j + 1]]
        if len(v) == 0:
            continue
        echoes = v[np.isfinite(v)]
        out_b.append((j + 0.5) * 2 * math.pi / bins)
        out_d.append(float(np.median(echoes)) if 2 * len(echoes) > len(v) else math.inf)
    return np.array(out_b), np.array(out_d)


def _sloped(
    b: np.ndarray,
    d: np.ndarray,
    claimed: np.ndarray,
    counted: list[int],
    tol_m: float,
    tol_rel: float,
    fewest: int,
) -> list[tuple[float, float, int, int]]:
    """The plateaus among the readings no counted run holds that border a lower run, joined
    over readings with no echo: a recess's back wall answers by specular reflection and
    side lobes, half of which drop out (fig16's indent, seed 1: three pieces over 35
    degrees, none long enough to count)."""
    open_ = np.where(np.isin(claimed, counted), claimed, -1)
    seeds = [(int(i), d[i] + tol_m + tol_rel * d[i]) for i in np.argsort(d, kind="stable")]
    seeds = [(i, limit) for i, limit in seeds if math.isfinite(limit)]
    return [r for r, slope in _joined(b, d, open_, seeds, fewest) if slope]


def _joined(
    b: np.ndarray,
    d: np.ndarray,
    open_: np.ndarray,
    seeds: list[tuple[int, float]],
    fewest: int,
) -> list[tuple[tuple[float, float, int, int], bool]]:
    """Runs grown from each seed (reading, limit) not yet held in ``open_``, joined over
    readings with no echo, each with whether it borders a lower run; only those of at least
    ``fewest`` readings on their plateau, short of the whole circle. ``open_`` records them."""
    n = len(d)
    out = []
    for i, limit in seeds:
        if open_[i] >= 0:
            continue
        lo, hi, slope = _grow(d, open_, i, limit, False, True)
        idx, member = _span(d, lo, hi, limit)
        open_[idx] = n + i
        if len(idx) < n and len(member) >= fewest:
            out.append((_run(b, d, idx, member, lo, hi), slope))
    return out


def _recessed(
    run: tuple[float, float, int, int],
    runs: list[tuple[float, float, int, int]],
    b: np.ndarray,
    d: np.ndarray,
    step_m: float,
) -> bool:
    """Whether ``run`` is a recess's back wall: at least ``RECESS_MIN_RAD`` wide, the runs of
    ``runs`` (in bearing order) on either side of it each at least ``step_m`` nearer, within
    ``RECESS_FRAME_RAD`` beyond its end, and a view between it and one of them deeper than
    it and than the vertex of a bend between the two: the recess's inner corner. Without one
    it is the middle face of a concave bend, joined to both (fig12's cut corner, seed 1:
    faces 1.41 m and 1.44 m off, the middle 1.53 m, read as a meet point of degree 4
    mid-room)."""
    two_pi, n = 2 * math.pi, len(d)
    dist, mid, lo, hi = run
    others = [r for r in runs if r != run]
    if len(others) < 2 or (b[hi] - b[lo]) % two_pi < RECESS_MIN_RAD:
        return False
    after = min(others, key=lambda r: (r[1] - mid) % two_pi)
    before = max(others, key=lambda r: (r[1] - mid) % two_pi)
    if not (
        before[0] <= dist - step_m
        and after[0] <= dist - step_m
        and (b[lo] - b[before[3]]) % two_pi <= RECESS_FRAME_RAD
        and (b[after[2]] - b[hi]) % two_pi <= RECESS_FRAME_RAD
    ):
        return False
    sides = (
        (before, range(before[3] + 1, before[3] + 1 + (lo - before[3] - 1) % n)),
        (after, range(hi + 1, hi + 1 + (after[2] - hi - 1) % n)),
    )
    for frame, gap in sides:
        between = np.array([d[k % n] for k in gap])
        seen = between[np.isfinite(between)]
        # No deeper than the vertex the run and its frame would make as two faces of one
        # bend: that is the bend's own vertex region (fig12's cut corner, seed 3: faces
        # 1.38 m and 1.37 m off, its vertex read as a plateau 1.47 m off, one reading 1.56 m
        # by it, short of the 1.58 m such a bend allows, and read as a recess mid-room).
        sep = min((mid - frame[1]) % two_pi, (frame[1] - mid) % two_pi)
        deep = max(dist + step_m, _bend_vertex(frame[0], dist, sep))
        if np.any(seen > deep):
            return True
    return False


def _span(d: np.ndarray, lo: int, hi: int, limit: float) -> tuple[np.ndarray, np.ndarray]:
    """The indices of readings ``lo`` to ``hi`` (unwrapped), and those of them within
    ``limit``: a run's readings and its plateau."""
    idx = np.array([k % len(d) for k in range(lo, hi + 1)])
    return idx, idx[d[idx] <= limit]


def _run(
    b: np.ndarray, d: np.ndarray, idx: np.ndarray, member: np.ndarray, lo: int, hi: int
) -> tuple[float, float, int, int]:
    """A run as (distance, mid bearing, lo, hi): the middle of the plateau is the mean of
    its end bearings, unwrapped across 0."""
    n = len(d)
    first, last = b[idx[0]], b[idx[-1]]
    mid = first + 0.5 * ((last - first) % (2 * math.pi))
    return float(np.median(d[member])), mid, lo % n, hi % n


def _grow(
    d: np.ndarray, claimed: np.ndarray, i: int, limit: float, bridge: bool, silent: bool
) -> tuple[int, int, bool]:
    """The run of readings within ``limit`` around reading ``i``, as (lo, hi) indices
    (unwrapped), and whether it borders another run (a slope). ``bridge`` reaches over one
    reading off the plateau, ``silent`` over one with no echo."""
    n = len(d)
    lo = hi = i
    slope = False
    for step in (1, -1):
        while hi - lo + 1 < n:
            k = (hi + 1) % n if step > 0 else (lo - 1) % n
            if claimed[k] >= 0:
                # A run claimed it first, from a lower reading: this one is its slope. Joining
                # pieces (``silent``) comes after every run, so only a lower neighbour counts.
                slope = slope or not silent or d[k] <= limit
                break
            if d[k] > limit:
                over = bridge or (silent and not math.isfinite(d[k]))
                if over and _on_plateau(d, claimed, (k + step) % n, limit, hi - lo + 2 < n):
                    if step > 0:
                        hi += 2
                    else:
                        lo -= 2
                    continue
                break
            if step > 0:
                hi += 1
            else:
                lo -= 1
    return lo, hi, slope


def _on_plateau(d: np.ndarray, claimed: np.ndarray, k: int, limit: float, room: bool) -> bool:
    """Whether reading ``k``, just past one off the plateau, is on it again."""
    return room and claimed[k] < 0 and d[k] <= limit


def _bend_vertex(
    a: float, c: float, sep: float, tol_m: float = 0.05, tol_rel: float = 0.03
) -> float:
    """The farthest a reading between two faces of one bent wall can be: the distance of the
    vertex where the faces' lines, ``a`` and ``c`` off along normals ``sep`` apart, meet, plus
    the sonar's noise. A wall is continuous round its bend, and each reading is the
    nearest echo in its beam, so none between the faces reaches beyond the vertex. Past a
    wall's end the view goes deeper: at fig16's indent the corridor's meet point sees the
    indent's near corner 1.11 m off and its back wall 1.25 m off, 42 degrees apart, and
    between them the inner corner 1.44 m off, beyond the 1.28 m vertex such a bend would
    have; joined as one bent wall, the corner and the wall hid the meet point from the sweep.
    """
    if sep < math.radians(5.0):
        return math.inf  # one flat wall: its readings between say nothing of a bend
    r = math.sqrt(a * a + c * c - 2.0 * a * c * math.cos(sep)) / math.sin(sep)
    return r + tol_m + tol_rel * r


def _shallow_bend(
    d: np.ndarray, k: int, end: int, far: float, agree: bool = False
) -> bool | None:
    """Whether the readings from ``k`` up to ``end`` show the vertex of a shallow concave
    bend between two faces at most ``far`` away: echoes all the way, none deeper than a bend
    of some 55 degrees would give. Each face answers only on its own side of the bend, so
    the middles of their plateaus lie wider apart than their normals: fig12's 45-degree cut
    corner read 62 and 71 degrees apart once dropouts no longer cut one face out (``silent``).
    A square corner's vertex is 1.41 times as far as its walls, and between two obstacles
    of a meet point the view goes past them. One deeper reading among them is a stray echo
    or a view too narrow to count, as for a bend within ``merge_rad`` (None: doubtful); with
    ``agree``, so are several that do not see about as far as one another."""
    n = len(d)
    between = d[[(k + j) % n for j in range((end - k) % n)]]
    seen = between[np.isfinite(between)]
    deeper = [float(x) for x in seen[seen > SHALLOW_BEND_RATIO * far]]
    deep = len(deeper)
    if len(seen) - deep < MIN_VIEW_READINGS or _view(deeper, agree) >= MIN_VIEW_READINGS:
        return False
    return True if deep == 0 else None


def _one_wall(
    a: tuple[float, float, int, int],
    c: tuple[float, float, int, int],
    d: np.ndarray,
    merge_rad: float,
    bend_ratio: float,
    shallow: bool = False,
    vertex: bool = False,
    agree: bool = False,
    silent_view: bool = False,
) -> bool | None:
    """``c`` follows ``a`` counter-clockwise; could the two be one bent wall? None: yes, but
    a view between them too narrow to count was seen (a stray echo, or a narrow doorway).
    With ``agree`` the deeper readings of a view see about as far; with ``silent_view`` a
    long enough stretch with no echo is a view (``SILENT_VIEW_READINGS``)."""
    sep = (c[1] - a[1]) % (2 * math.pi)
    if sep >= (BENT_WALL_MAX_RAD if shallow else merge_rad):
        return False
    if max(a[0], c[0]) > bend_ratio * min(a[0], c[0]):
        return False  # a flat bend's two faces are about equally far
    n = len(d)
    k, end = (a[3] + 1) % n, c[2]
    far = max(a[0], c[0])
    if silent_view and _silent_view(d, k, end, bend_ratio * far):
        return False
    if sep >= merge_rad:
        return _shallow_bend(d, k, end, far, agree)
    limit = bend_ratio * far
    if vertex:
        # Never nearer than a shallow bend's vertex (``SHALLOW_BEND_RATIO``): the middles of
        # two runs can lie closer in bearing than the faces' normals. fig12's cut corner
        # (seed 29 at 417 s) read two runs 1.38 m off 22 degrees apart, a vertex of 1.41 m,
        # and four readings of 1.49-1.52 m between them made its faces two walls and a meet
        # point that is not there.
        limit = min(limit, max(_bend_vertex(a[0], c[0], sep), SHALLOW_BEND_RATIO * far))
    # A view past the bend is some degrees wide; one stray reading is not (an outlier, and a
    # ring that fires fast sweeps hundreds of readings, outliers among them). Each reading
    # stands for the sweep's mean spacing: two deeper readings separate on a slow ring.
    # With ``agree``, only if they see about as far (a doorway's readings all meet the next
    # room's wall): fig12 seed 76 read 2.1 m and 5.7 m amid its cut corner's 1.4 m, and the
    # corner's two faces made a meet point that is not there.
    deep: list[float] = []
    while k != end:
        if math.isfinite(d[k]) and d[k] > limit:
            deep.append(float(d[k]))
        k = (k + 1) % n
    view = _view(deep, agree)
    if view >= MIN_VIEW_READINGS and view * 2 * math.pi / n >= MIN_VIEW_RAD:
        return False
    return True if not deep else None


def _silent_view(d: np.ndarray, k: int, end: int, near_m: float) -> bool:
    """Whether readings ``k`` up to ``end`` (exclusive, round the sweep) hold a run of no echo
    ``SILENT_VIEW_READINGS`` long and ``SILENT_VIEW_RAD`` wide, and none nearer than
    ``near_m`` but the two next to the runs (a jamb's edge of the beam)."""
    n = len(d)
    between = [float(d[(k + j) % n]) for j in range((end - k) % n)]
    if any(x <= near_m for x in between[1:-1]):
        return False
    longest = run = 0
    for x in between:
        run = 0 if math.isfinite(x) else run + 1
        longest = max(longest, run)
    return longest >= SILENT_VIEW_READINGS and longest * 2 * math.pi / n >= SILENT_VIEW_RAD


def _view(distances: list[float], agree: bool) -> int:
    """How many readings of a view past a bend ``distances`` (the deeper ones) make: all of
    them, or with ``agree`` the most that lie within ``VIEW_AGREE_REL`` of one another."""
    if not agree:
        return len(distances)
    v = sorted(distances)
    best, lo = 0, 0
    for hi, x in enumerate(v):
        while x > v[lo] * (1.0 + VIEW_AGREE_REL):
            lo += 1
        best = max(best, hi - lo + 1)
    return best

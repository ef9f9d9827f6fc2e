"""Built-in worlds: the environments of the paper's figures and seeded office and maze generators.

The figure worlds approximate the environments of Choset & Nagatani (Figs. 1, 12-16) closely
enough to reproduce the *topology* each figure is about (a single cycle, a lab whose doors open
onto corridors, a hypersymmetric grid, a weak meet point); exact dimensions were never published
beyond the floor areas, so the layouts below are plausible reconstructions in metres.

Every world is sized for a Nomad 200: a 0.23 m radius disk whose sonar sees 6.5 m beyond its
skin. So every free point stays within about 6 m of a wall (otherwise the robot would see
nothing and the GVG would be undefined from its sensors), corridors are at least 1.2 m and doors
at least 0.9 m wide, and no two walls come closer than 0.8 m except where they join.

The generators work in integer decimetres and only convert to metres at the end: rectangles
then meet exactly, unions have no slivers, and a seed reproduces the same world bit for bit on
every platform (``numpy.random.default_rng`` streams are only promised stable within a numpy
release line, so a numpy upgrade may change what a seed draws).
"""

from __future__ import annotations

import itertools
import math
import re
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import shapely
from shapely import affinity
from shapely.geometry import Polygon, box
from shapely.ops import unary_union

from sim_backend.world import PolygonWorld, StartPose, WorldError

ROBOT_RADIUS_M = 0.23
"""Nomad 200 footprint radius; every built-in start pose must clear walls by this much."""

Rect = tuple[float, float, float, float]
"""An axis-aligned rectangle ``(x0, y0, x1, y1)`` with ``x0 < x1`` and ``y0 < y1``."""

_SEEDED = ("office", "maze")
_SEED_RE = re.compile(r"[0-9]+")


def _box(x0: float, y0: float, x1: float, y1: float) -> list[tuple[float, float]]:
    return [(x0, y0), (x1, y0), (x1, y1), (x0, y1)]


# ---------------------------------------------------------------------------------------------
# The paper's figures
# ---------------------------------------------------------------------------------------------


def _fig1() -> PolygonWorld:
    """Fig. 1: the 7 x 14 m linoleum floor of the dead-reckoning experiment (Fig. 7).

    A long central block makes the one cycle the robot closes when it backtracks to meet
    point 1; a partition between two bays, an alcove behind a wall stub, a cabinet and a short
    wall stub hang branches (and boundary edges into the room corners) off that cycle, giving
    about ten meet points.
    """
    obstacles = [
        _box(2.5, 4.0, 4.5, 10.0),  # central block: the cycle
        _box(3.4, -0.1, 3.6, 2.2),  # partition splitting the bottom into two bays
        _box(5.0, 11.9, 7.1, 12.1),  # wall stub closing an alcove in the top-right corner
        _box(-0.1, 11.0, 0.8, 12.5),  # cabinet against the left wall
        _box(-0.1, 6.4, 0.9, 6.6),  # short stub in the left corridor
    ]
    return PolygonWorld(
        "fig1", _box(0.0, 0.0, 7.0, 14.0), obstacles, StartPose(1.25, 5.0, math.pi / 2)
    )


def _fig12() -> PolygonWorld:
    """Fig. 12: a room around one central obstacle, so the GVG has exactly one cycle.

    The block is off centre and one room corner is cut off: in a perfectly symmetric room
    every meet point on the cycle would look alike, which is Fig. 15's problem, not this one's.
    """
    boundary = [(0.0, 0.0), (8.0, 0.0), (8.0, 6.8), (6.8, 8.0), (0.0, 8.0)]
    return PolygonWorld(
        "fig12", boundary, [_box(2.3, 2.6, 5.3, 5.6)], StartPose(1.15, 4.0, math.pi / 2)
    )


_LAB = (0.0, 0.0, 10.5, 7.5)
"""Interior of the Sensor-Based Planning lab of Figs. 13 and 14 (about 79 m2 before furniture)."""

_LAB_FURNITURE = [
    _box(3.0, 3.0, 5.0, 4.5),  # table in the middle of the room: first cycle
    _box(6.8, 2.5, 8.3, 5.0),  # second table: second cycle
    _box(-0.1, 5.0, 0.6, 7.6),  # cabinet in the top-left corner
    _box(7.0, -0.1, 9.0, 0.6),  # cabinet against the bottom wall
    _box(4.0, 6.8, 6.0, 7.6),  # desk against the top wall
]
"""Furniture overlapping the walls it stands against, so no sliver of floor is left behind it."""

_LAB_START = StartPose(1.5, 1.5, 0.0)


def _fig13() -> PolygonWorld:
    """Fig. 13: the 750 ft2 (70 m2) lab with both doors closed.

    The closed doors are plain wall here; ``fig14`` opens them in the same places (bottom wall
    at x 1.5-2.5, right wall at y 5.6-6.6), which is where the paper's meet points 9 and 10 sit.
    """
    return PolygonWorld("fig13", _box(*_LAB), _LAB_FURNITURE, _LAB_START)


def _fig14() -> PolygonWorld:
    """Fig. 14: the fig13 lab, doors open, inside the ring of hallways around it (1800 ft2).

    The lab keeps fig13's coordinates and furniture, so the two worlds agree everywhere inside
    the lab; 0.2 m walls with two 1 m door gaps separate it from 1.8-2.2 m corridors, and a
    dead-end side corridor adds a branch the robot must explore and backtrack from.
    """
    x0, y0, x1, y1 = _LAB
    t = 0.2
    walls = [
        _box(x0 - t, y0 - t, 1.5, y0),  # bottom wall, left of the bottom door
        _box(2.5, y0 - t, x1 + t, y0),  # bottom wall, right of the bottom door
        _box(x0 - t, y1, x1 + t, y1 + t),  # top wall
        _box(x0 - t, y0 - t, x0, y1 + t),  # left wall
        _box(x1, y0 - t, x1 + t, 5.6),  # right wall, below the right door
        _box(x1, 6.6, x1 + t, y1 + t),  # right wall, above the right door
    ]
    boundary = [
        (-2.0, -2.2),
        (8.0, -2.2),
        (8.0, -6.5),  # dead-end side corridor, 2 m wide and 4.3 m long
        (10.0, -6.5),
        (10.0, -2.2),
        (12.9, -2.2),
        (12.9, 9.9),
        (-2.0, 9.9),
    ]
    return PolygonWorld("fig14", boundary, walls + _LAB_FURNITURE, _LAB_START)


def _fig15() -> PolygonWorld:
    """Fig. 15: identical 2 x 2 m blocks on a 3.5 m pitch with 1.5 m aisles everywhere.

    Every aisle crossing is a four-way meet point with the same departure angles and the same
    edge lengths to its neighbours, so topology alone cannot tell them apart.
    """
    offsets = [1.5, 5.0, 8.5]
    blocks = [_box(x, y, x + 2.0, y + 2.0) for y in offsets for x in offsets]
    return PolygonWorld("fig15", _box(0.0, 0.0, 12.0, 12.0), blocks, StartPose(4.25, 4.25, 0.0))


def _fig16() -> PolygonWorld:
    """Fig. 16: a 2 m corridor with a 0.4 m deep, 1.5 m long indent on its right-hand side.

    The indent is shallow enough that small sonar changes decide whether the GVG grows a meet
    point (and a boundary edge into the indent) there: the paper's weak meet point.
    """
    boundary = [
        (0.4, 0.0),
        (2.4, 0.0),
        (2.4, 12.0),
        (0.4, 12.0),
        (0.4, 6.75),
        (0.0, 6.75),  # the indent, on the right of a robot driving down (-y) from the top
        (0.0, 5.25),
        (0.4, 5.25),
    ]
    return PolygonWorld("fig16", boundary, [], StartPose(1.4, 11.0, -math.pi / 2))


_FIGURES: dict[str, Callable[[], PolygonWorld]] = {
    "fig1": _fig1,
    "fig12": _fig12,
    "fig13": _fig13,
    "fig14": _fig14,
    "fig15": _fig15,
    "fig16": _fig16,
}


# ---------------------------------------------------------------------------------------------
# Seeded generators (integer decimetres internally)
# ---------------------------------------------------------------------------------------------

_WALL_DM = 2  # wall thickness: 0.2 m
_MIN_EXTENT_DM = 505  # free space must span at least 50 m; a little margin over 500


@dataclass(frozen=True)
class OfficePlan:
    """What ``office_world`` drew, in metres, so tests and tools can check it against the brief.

    Rooms, corridors and doors are the *clear* free rectangles (wall thickness excluded); a
    door rectangle spans the wall it pierces and overlaps the free space on both sides.
    """

    seed: int
    wall_m: float
    corridors: tuple[Rect, ...]
    rooms: tuple[Rect, ...]
    doors: tuple[Rect, ...]
    room_of_door: tuple[int, ...]
    furniture: tuple[Rect, ...]
    start: StartPose


@dataclass(frozen=True)
class MazePlan:
    """What ``maze_world`` drew: an ``n x n`` grid of square cells and the walls it removed.

    An opening is ``((row, col), (row, col))`` between two neighbouring cells. The first
    ``n * n - 1`` openings form a spanning tree (the perfect maze); ``extra_openings`` are the
    additional ones, each closing exactly one cycle.
    """

    seed: int
    n: int
    cell_m: float
    wall_m: float
    openings: tuple[tuple[tuple[int, int], tuple[int, int]], ...]
    extra_openings: tuple[tuple[tuple[int, int], tuple[int, int]], ...]
    start: StartPose


def _dm_rect(r: tuple[int, int, int, int]) -> Rect:
    return (r[0] / 10, r[1] / 10, r[2] / 10, r[3] / 10)


def _partition(rng: np.random.Generator, total: int, lo: int, hi: int) -> list[int]:
    """Split ``total`` into parts within ``[lo, hi]``; needs ``total >= lo`` and ``hi >= 2 * lo``.

    Taking ``lo..min(hi, rest - lo)`` each time always leaves a remainder of at least ``lo``,
    which is itself a legal part once it drops to ``hi`` or less: no rejection loop is needed.
    """
    parts: list[int] = []
    rest = total
    while rest > hi:
        part = int(rng.integers(lo, min(hi, rest - lo) + 1))
        parts.append(part)
        rest -= part
    parts.append(rest)
    return parts


def office_plan(seed: int) -> OfficePlan:
    """Lay out an office floor: a grid of corridors with rooms off them, every room with a door.

    Horizontal corridors run the full width and vertical corridors the full height, so the
    corridors form a grid with cycles and their ends are dead ends (boundary edges). Between
    corridors lie bands of rooms two deep, back to back; the outermost bands are one room deep
    against the outer wall. Each room has one door onto its corridor; a few neighbouring rooms
    also share a door (more cycles); about half hold a table or a cabinet.
    """
    rng = np.random.default_rng(seed)
    t = _WALL_DM
    half = t // 2

    # Along x: room segments separated by vertical corridors.
    n_vc = int(rng.integers(2, 4))
    vc_widths = [int(rng.integers(15, 26)) for _ in range(n_vc)]
    target_w = int(rng.integers(_MIN_EXTENT_DM + t, 561))
    n_seg = n_vc + 1
    min_seg = 90
    spare = target_w - sum(w + t for w in vc_widths) - n_seg * min_seg
    seg_widths = [min_seg + int(e) for e in rng.multinomial(spare, [1.0 / n_seg] * n_seg)]
    x_segments: list[tuple[int, int]] = []
    vcorridors: list[tuple[int, int]] = []
    x = 0
    for k in range(n_seg):
        x_segments.append((x, x + seg_widths[k]))
        x += seg_widths[k]
        if k < n_vc:
            vcorridors.append((x, x + vc_widths[k] + t))
            x += vc_widths[k] + t
    width = x

    # Along y: corridors, and rows of rooms facing the corridor above ("up") or below ("down").
    rows: list[tuple[int, int, str]] = []  # (y0, y1, side its corridor is on)
    hcorridors: list[tuple[int, int]] = []
    target_h = int(rng.integers(_MIN_EXTENT_DM + t, 561))

    def depth() -> int:
        return int(rng.integers(32, 81))  # 3.0-7.8 m clear once the wall is taken off

    def add_corridor(y: int) -> int:
        w = int(rng.integers(15, 26)) + t
        hcorridors.append((y, y + w))
        return y + w

    y = 0
    d = depth()
    rows.append((y, y + d, "up"))
    y = add_corridor(y + d)
    while y + 80 < target_h:
        d = depth()
        rows.append((y, y + d, "down"))
        y += d
        d = depth()
        rows.append((y, y + d, "up"))
        y = add_corridor(y + d)
    d = int(rng.integers(max(32, target_h - y), 81))
    rows.append((y, y + d, "down"))
    height = y + d

    corridors = [(-half, c0 + half, width + half, c1 - half) for c0, c1 in hcorridors]
    corridors += [(c0 + half, -half, c1 - half, height + half) for c0, c1 in vcorridors]
    # Outer walls are the boundary itself: pull corridor ends back inside them.
    corridors = [
        (max(a, half), max(b, half), min(c, width - half), min(e, height - half))
        for a, b, c, e in corridors
    ]

    rooms: list[tuple[int, int, int, int]] = []
    doors: list[tuple[int, int, int, int]] = []
    room_of_door: list[int] = []
    furniture: list[tuple[int, int, int, int]] = []
    for ry0, ry1, side in rows:
        for sx0, sx1 in x_segments:
            xs = [sx0]
            for w in _partition(rng, sx1 - sx0, 32, 80):
                xs.append(xs[-1] + w)
            row_rooms: list[int] = []
            for a, b in itertools.pairwise(xs):
                room = (a + half, ry0 + half, b - half, ry1 - half)
                rooms.append(room)
                row_rooms.append(len(rooms) - 1)
                dw = int(rng.integers(9, 13))
                dx = int(rng.integers(room[0] + 3, room[2] - 3 - dw + 1))
                wall_y = ry1 if side == "up" else ry0
                doors.append((dx, wall_y - half - 1, dx + dw, wall_y + half + 1))
                room_of_door.append(len(rooms) - 1)
                furniture.extend(_furnish(rng, room, side))
            # Occasionally a door between neighbours in the row, kept 1 m off the back wall
            # so it never opens onto a cabinet.
            for left in row_rooms[:-1]:
                if rng.random() >= 0.15:
                    continue
                r = rooms[left]
                dw = int(rng.integers(9, 13))
                if side == "up":  # the back wall (and any cabinet) is at the bottom
                    lo, hi = r[1] + 10, r[3] - 3 - dw
                else:
                    lo, hi = r[1] + 3, r[3] - 10 - dw
                dy = int(rng.integers(lo, hi + 1))
                wall_x = r[2] + half
                doors.append((wall_x - half - 1, dy, wall_x + half + 1, dy + dw))
                room_of_door.append(left)

    c0, c1 = hcorridors[0]
    sx0, sx1 = x_segments[0]
    start = StartPose((sx0 + sx1) / 20, (c0 + c1) / 20, 0.0)
    return OfficePlan(
        seed=seed,
        wall_m=t / 10,
        corridors=tuple(_dm_rect(r) for r in corridors),
        rooms=tuple(_dm_rect(r) for r in rooms),
        doors=tuple(_dm_rect(r) for r in doors),
        room_of_door=tuple(room_of_door),
        furniture=tuple(_dm_rect(r) for r in furniture),
        start=start,
    )


def _furnish(
    rng: np.random.Generator, room: tuple[int, int, int, int], door_side: str
) -> list[tuple[int, int, int, int]]:
    """Maybe a table (1 m clear of every wall) or a cabinet on the wall opposite the door.

    The clearances keep every passage around furniture at least 1 m wide, so a room can never
    be split in two and the robot can always get round.
    """
    x0, y0, x1, y1 = room
    iw, ih = x1 - x0, y1 - y0
    kind = rng.random()
    if kind < 0.3 and iw >= 28 and ih >= 28:
        bw = int(rng.integers(8, min(20, iw - 20) + 1))
        bh = int(rng.integers(8, min(20, ih - 20) + 1))
        bx = int(rng.integers(x0 + 10, x1 - 10 - bw + 1))
        by = int(rng.integers(y0 + 10, y1 - 10 - bh + 1))
        return [(bx, by, bx + bw, by + bh)]
    if kind < 0.5:
        depth = int(rng.integers(5, 9))
        length = int(rng.integers(10, iw - 10 + 1))
        # The cabinet overlaps the back wall by 1 dm so no sliver of floor is left behind it.
        if door_side == "up":
            ya, yb = y0 - 1, y0 + depth
        else:
            ya, yb = y1 - depth, y1 + 1
        if rng.random() < 0.5:
            return [(x0 - 1, ya, x0 + length, yb)]
        return [(x1 - length, ya, x1 + 1, yb)]
    return []


def _world_from_free(name: str, free: object, start: StartPose) -> PolygonWorld:
    """Build a PolygonWorld whose boundary is the free region's outline and obstacles its holes.

    Generated worlds are unions of free rectangles; handing PolygonWorld the outline and the
    holes reproduces that union exactly with far fewer vertices than one rectangle per wall.
    """
    free = shapely.simplify(free, 0.0)  # drop collinear vertices left where rectangles joined
    if not isinstance(free, Polygon):
        n = len(getattr(free, "geoms", []))
        raise WorldError(f"{name}: generated free space falls into {n} pieces")
    boundary = np.asarray(free.exterior.coords)[:-1]
    holes = [np.asarray(r.coords)[:-1] for r in free.interiors]
    world = PolygonWorld(name, boundary, holes, start, source=f"builtin:{name}")
    world.check_start(ROBOT_RADIUS_M)
    return world


def office_world(seed: int) -> PolygonWorld:
    """The office floor of ``office_plan(seed)`` as a world named ``office:SEED``."""
    plan = office_plan(seed)

    def dm_box(r: Rect) -> Polygon:
        # Back to exact integers: rectangles sharing an edge then share it bit for bit.
        return box(*(round(v * 10) for v in r))

    free = unary_union([dm_box(r) for r in plan.corridors + plan.rooms + plan.doors])
    if plan.furniture:
        free = free.difference(unary_union([dm_box(r) for r in plan.furniture]))
    free = affinity.scale(free, 0.1, 0.1, origin=(0, 0))
    return _world_from_free(f"office:{seed}", free, plan.start)


def maze_plan(seed: int) -> MazePlan:
    """A recursive-backtracker maze (long winding passages) plus a few extra openings.

    The extra openings turn the tree into a graph with cycles, as real mazes and buildings
    have; an opening is skipped when it would leave a wall post standing alone as a 0.2 m
    pillar, which would add a meaningless cycle and a meet point around a speck.
    """
    rng = np.random.default_rng(seed)
    t = _WALL_DM
    cell = int(rng.integers(22, 31))  # 2.2-3.0 m cells: passages 2.0-2.8 m wide
    n = -(-(_MIN_EXTENT_DM + t) // cell)
    visited = np.zeros((n, n), dtype=bool)
    openings: list[tuple[tuple[int, int], tuple[int, int]]] = []
    stack = [(0, 0)]
    visited[0, 0] = True
    while stack:
        r, c = stack[-1]
        nbrs = [
            (r + dr, c + dc)
            for dr, dc in ((1, 0), (-1, 0), (0, 1), (0, -1))
            if 0 <= r + dr < n and 0 <= c + dc < n and not visited[r + dr, c + dc]
        ]
        if not nbrs:
            stack.pop()
            continue
        nxt = nbrs[int(rng.integers(len(nbrs)))]
        visited[nxt] = True
        openings.append(((r, c), nxt))
        stack.append(nxt)

    opened = {frozenset(o) for o in openings}
    closed = [
        ((r, c), (r + dr, c + dc))
        for r in range(n)
        for c in range(n)
        for dr, dc in ((1, 0), (0, 1))
        if r + dr < n and c + dc < n and frozenset({(r, c), (r + dr, c + dc)}) not in opened
    ]
    n_extra = max(3, n * n // 40)
    extra: list[tuple[tuple[int, int], tuple[int, int]]] = []
    for i in rng.permutation(len(closed)):
        if len(extra) == n_extra:
            break
        a, b = closed[int(i)]
        if _isolates_post(opened, a, b, n):
            continue
        opened.add(frozenset((a, b)))
        extra.append((a, b))

    start = StartPose(cell / 20, cell / 20, 0.0)
    return MazePlan(
        seed=seed,
        n=n,
        cell_m=cell / 10,
        wall_m=t / 10,
        openings=tuple(openings + extra),
        extra_openings=tuple(extra),
        start=start,
    )


def _isolates_post(
    opened: set[frozenset[tuple[int, int]]],
    a: tuple[int, int],
    b: tuple[int, int],
    n: int,
) -> bool:
    """Would opening the wall between cells ``a`` and ``b`` free-stand one of its end posts?

    A post at lattice point (row R, col C) touches cells (R-1..R, C-1..C); it stands alone when
    all four walls meeting there are open. Posts on the outer wall are always anchored.
    """
    (_, c0), (r1, c1) = sorted((a, b))
    # Lattice points at the two ends of the wall between the cells.
    ends = [(r1, c1), (r1 + 1, c1)] if c1 != c0 else [(r1, c1), (r1, c1 + 1)]
    trial = opened | {frozenset((a, b))}
    for pr, pc in ends:
        if not (0 < pr < n and 0 < pc < n):
            continue
        walls = [
            ((pr - 1, pc - 1), (pr - 1, pc)),
            ((pr, pc - 1), (pr, pc)),
            ((pr - 1, pc - 1), (pr, pc - 1)),
            ((pr - 1, pc), (pr, pc)),
        ]
        if all(frozenset(w) in trial for w in walls):
            return True
    return False


def maze_world(seed: int) -> PolygonWorld:
    """The maze of ``maze_plan(seed)`` as a world named ``maze:SEED``."""
    plan = maze_plan(seed)
    c = round(plan.cell_m * 10)
    half = _WALL_DM // 2
    rects = [
        box(col * c + half, row * c + half, (col + 1) * c - half, (row + 1) * c - half)
        for row in range(plan.n)
        for col in range(plan.n)
    ]
    for (r0, c0), (r1, c1) in plan.openings:
        r, col = min(r0, r1), min(c0, c1)
        if r0 == r1:  # neighbours in a row: pierce the vertical wall between them
            wx = (col + 1) * c
            rects.append(box(wx - half - 1, r * c + half, wx + half + 1, (r + 1) * c - half))
        else:
            wy = (r + 1) * c
            rects.append(box(col * c + half, wy - half - 1, (col + 1) * c - half, wy + half + 1))
    free = affinity.scale(unary_union(rects), 0.1, 0.1, origin=(0, 0))
    return _world_from_free(f"maze:{seed}", free, plan.start)


# ---------------------------------------------------------------------------------------------
# Names
# ---------------------------------------------------------------------------------------------


def builtin_names() -> list[str]:
    """The names ``load_world`` accepts besides file paths; ``SEED`` is any integer >= 0."""
    return [*_FIGURES, *(f"{g}:SEED" for g in _SEEDED)]


def is_builtin_name(spec: str) -> bool:
    """True when ``spec`` names a built-in (even with a bad seed), so it is never a file path.

    ``office:abc`` counts: it is meant as a built-in, and the user should hear that the seed is
    wrong rather than that no file of that name exists.
    """
    return spec in _FIGURES or (":" in spec and spec.split(":", 1)[0] in _SEEDED)


def builtin_world(name: str) -> PolygonWorld:
    """Build a built-in world: ``fig1`` ... ``fig16``, ``office:SEED`` or ``maze:SEED``.

    Figure worlds are rebuilt on every call (they are tiny), so callers may mutate the result.
    """
    if name in _FIGURES:
        world = _FIGURES[name]()
        world.source = f"builtin:{name}"
        world.check_start(ROBOT_RADIUS_M)
        return world
    kind, sep, seed_text = name.partition(":")
    if sep and kind in _SEEDED:
        if not _SEED_RE.fullmatch(seed_text):
            raise WorldError(f"{name}: the seed must be a non-negative integer, got {seed_text!r}")
        seed = int(seed_text)
        return office_world(seed) if kind == "office" else maze_world(seed)
    raise WorldError(
        f"{name}: unknown built-in world; valid names are {', '.join(builtin_names())}"
    )

"""Built-in worlds: sizes from the paper, the topology each figure is about, and the rules every
world must keep for a Nomad 200 (room for the robot, no slivers, walls within sonar range).
"""

from __future__ import annotations

import itertools
import time

import numpy as np
import pytest
from shapely.geometry import LinearRing, Polygon, box
from shapely.ops import unary_union

from sim_backend.builtin_worlds import (
    ROBOT_RADIUS_M,
    builtin_names,
    builtin_world,
    maze_plan,
    maze_world,
    office_plan,
    office_world,
)
from sim_backend.world import PolygonWorld, WorldError, point_segments_distance
from sim_backend.world_files import load_world

FIGURES = ["fig1", "fig12", "fig13", "fig14", "fig15", "fig16"]
SEEDED = ["office:0", "office:7", "office:123", "maze:0", "maze:7", "maze:123"]


@pytest.fixture(scope="module")
def worlds() -> dict[str, PolygonWorld]:
    return {name: builtin_world(name) for name in FIGURES + SEEDED}


def free_samples(world: PolygonWorld, spacing: float) -> np.ndarray:
    x0, y0, x1, y1 = world.bounds
    xs, ys = np.meshgrid(np.arange(x0, x1, spacing), np.arange(y0, y1, spacing))
    pts = np.column_stack([xs.ravel(), ys.ravel()]) + spacing / 2
    return pts[world.is_free(pts)]


def vertex_count(world: PolygonWorld) -> int:
    return len(world.boundary) + sum(len(o) for o in world.obstacles)


@pytest.mark.parametrize("name", FIGURES + SEEDED)
def test_world_is_named_connected_and_the_robot_fits_at_start(worlds, name):
    world = worlds[name]
    assert world.name == name
    assert world.source == f"builtin:{name}"
    assert isinstance(world.free_region, Polygon)  # a single connected free region
    start = np.array([[world.start.x, world.start.y]])
    assert world.is_free(start)[0]
    assert point_segments_distance(start, world.segments)[0] >= ROBOT_RADIUS_M


@pytest.mark.parametrize("name", FIGURES + SEEDED)
def test_every_free_point_is_within_sonar_range_of_a_wall(worlds, name):
    world = worlds[name]
    pts = free_samples(world, 0.5 if name in FIGURES else 1.0)
    assert len(pts) > 0.8 * world.free_area_m2 / (0.25 if name in FIGURES else 1.0)
    assert point_segments_distance(pts, world.segments).max() <= 6.0


@pytest.mark.parametrize("name", FIGURES + SEEDED)
def test_no_gap_is_narrower_than_a_door(worlds, name):
    """Distinct walls stay 0.8 m apart, and shrinking free space by 0.44 m (so every passage
    narrower than 0.88 m closes) leaves it in one piece: every door and corridor is passable."""
    free = worlds[name].free_region
    rings = [Polygon(free.exterior.coords), *(Polygon(r.coords) for r in free.interiors)]
    outer = LinearRing(free.exterior.coords)
    for a, b in itertools.combinations(range(len(rings)), 2):
        geom_a = outer if a == 0 else rings[a]
        assert geom_a.distance(rings[b]) >= 0.8 - 1e-9, (name, a, b)
    eroded = free.buffer(-0.44, join_style="mitre")
    assert isinstance(eroded, Polygon)


def test_builtin_names_all_load():
    assert builtin_names() == [*FIGURES, "office:SEED", "maze:SEED"]
    for name in FIGURES:
        assert load_world(name).source == f"builtin:{name}"


# --- the figures --------------------------------------------------------------------------------


def test_fig1_is_the_7_by_14_m_loop_with_branches(worlds):
    world = worlds["fig1"]
    assert world.width_m == pytest.approx(7.0, abs=0.5)
    assert world.height_m == pytest.approx(14.0, abs=0.5)
    assert len(world.free_region.interiors) >= 1  # the loop
    # GVG branches run into concave (reflecting) corners; a bare room has only four.
    assert int((~world.corner_convex).sum()) >= 10


def test_fig12_has_exactly_one_cycle_and_no_symmetry(worlds):
    world = worlds["fig12"]
    free = world.free_region
    assert len(free.interiors) == 1  # one obstacle: the GVG has exactly one cycle
    hole = Polygon(free.interiors[0].coords)
    assert hole.area == pytest.approx(9.0)
    x0, y0, x1, y1 = world.bounds
    cx, cy = (x0 + x1) / 2, (y0 + y1) / 2
    for fx, fy in [(-1, 1), (1, -1), (-1, -1)]:
        mirrored = Polygon(
            [(cx + fx * (x - cx), cy + fy * (y - cy)) for x, y in free.exterior.coords]
        )
        assert mirrored.symmetric_difference(Polygon(free.exterior.coords)).area > 0.5
    # The central block is off-centre: aisles around it have different widths.
    bx0, by0, bx1, by1 = hole.bounds
    aisles = [bx0 - x0, by0 - y0, x1 - bx1, y1 - by1]
    assert len({round(a, 2) for a in aisles}) >= 3
    assert min(aisles) >= 1.2


def test_fig13_is_a_70_m2_lab_with_one_or_two_cycles(worlds):
    world = worlds["fig13"]
    assert 60.0 <= world.free_area_m2 <= 80.0
    assert 1 <= len(world.free_region.interiors) <= 2
    assert len(world.obstacles) >= 4  # tables and cabinets


def test_fig14_is_fig13_with_open_doors_and_corridors(worlds):
    lab, big = worlds["fig13"], worlds["fig14"]
    assert 150.0 <= big.free_area_m2 <= 190.0
    # Inside the lab the two worlds are identical.
    x0, y0, x1, y1 = lab.bounds
    xs, ys = np.meshgrid(
        np.linspace(x0 + 0.01, x1 - 0.01, 80), np.linspace(y0 + 0.01, y1 - 0.01, 60)
    )
    pts = np.column_stack([xs.ravel(), ys.ravel()])
    assert np.array_equal(lab.is_free(pts), big.is_free(pts))
    # The doors, closed in fig13, are open in fig14 and lead into corridors.
    doors = np.array([[2.0, -0.1], [10.6, 6.1]])
    corridors = np.array([[2.0, -1.2], [11.8, 6.1]])
    assert big.is_free(doors).all() and big.is_free(corridors).all()
    assert not lab.is_free(doors).any()
    assert lab.free_area_m2 + 80.0 < big.free_area_m2


def test_fig15_is_a_grid_of_identical_blocks_and_aisles(worlds):
    world = worlds["fig15"]
    holes = [Polygon(r.coords) for r in world.free_region.interiors]
    assert len(holes) == 9
    sizes = {
        (round(h.bounds[2] - h.bounds[0], 6), round(h.bounds[3] - h.bounds[1], 6)) for h in holes
    }
    assert sizes == {(2.0, 2.0)}
    gaps = {round(a.distance(b), 6) for a, b in itertools.combinations(holes, 2)}
    outer = LinearRing(world.free_region.exterior.coords)
    assert min(gaps) == pytest.approx(1.5)
    to_wall = sorted(round(outer.distance(h), 6) for h in holes)
    assert to_wall == [1.5] * 8 + [5.0]  # eight blocks along the walls, one in the middle
    # All nine blocks sit on one lattice: same pitch in x and in y.
    xs = sorted({round(h.bounds[0], 6) for h in holes})
    ys = sorted({round(h.bounds[1], 6) for h in holes})
    assert len(xs) == len(ys) == 3
    assert np.allclose(np.diff(xs), 3.5) and np.allclose(np.diff(ys), 3.5)


def test_fig16_is_a_corridor_with_a_shallow_indent(worlds):
    world = worlds["fig16"]
    assert len(world.free_region.interiors) == 0
    assert world.height_m == pytest.approx(12.0)

    def width_at(y: float) -> float:
        xs = np.linspace(world.bounds[0] - 1, world.bounds[2] + 1, 3401)
        return float(world.is_free(np.column_stack([xs, np.full_like(xs, y)])).sum()) * (
            xs[1] - xs[0]
        )

    corridor, indent = width_at(2.0), width_at(6.0)
    assert corridor == pytest.approx(2.0, abs=0.01)
    assert 0.3 <= indent - corridor <= 0.5
    indent_length = (world.free_area_m2 - 2.0 * 12.0) / (indent - corridor)
    assert 1.0 <= indent_length <= 2.0


# --- the generators -------------------------------------------------------------------------------


@pytest.mark.parametrize("make", [office_world, maze_world])
def test_generators_are_deterministic_and_seed_sensitive(make):
    a, b, c = make(11), make(11), make(12)
    assert np.array_equal(a.boundary, b.boundary)
    assert len(a.obstacles) == len(b.obstacles)
    assert all(np.array_equal(p, q) for p, q in zip(a.obstacles, b.obstacles, strict=True))
    assert a.free_area_m2 == b.free_area_m2
    assert a.free_region.symmetric_difference(c.free_region).area > 10.0


@pytest.mark.parametrize("name", [n for n in SEEDED])
def test_generated_worlds_are_large_and_light(worlds, name):
    world = worlds[name]
    assert world.width_m >= 50.0 and world.height_m >= 50.0
    assert vertex_count(world) <= 3000
    assert world.free_area_m2 >= 0.8 * 50.0 * 50.0


@pytest.mark.parametrize("make", [office_world, maze_world])
def test_generation_is_fast(make):
    t0 = time.perf_counter()
    world = make(2024)
    elapsed = time.perf_counter() - t0
    assert world.width_m >= 50.0
    assert elapsed < 2.0  # typically well under 0.1 s


@pytest.mark.parametrize("seed", [0, 7, 123])
def test_office_plan_respects_office_dimensions(worlds, seed):
    plan = office_plan(seed)
    world = worlds[f"office:{seed}"]
    dims = lambda r: (r[2] - r[0], r[3] - r[1])  # noqa: E731
    for room in plan.rooms:
        assert all(3.0 - 1e-9 <= d <= 8.0 + 1e-9 for d in dims(room))
    for corridor in plan.corridors:
        assert 1.5 - 1e-9 <= min(dims(corridor)) <= 2.5 + 1e-9
    for door in plan.doors:
        assert 0.9 - 1e-9 <= max(dims(door)) <= 1.2 + 1e-9
    assert set(plan.room_of_door) == set(range(len(plan.rooms)))  # every room has a door
    assert 0 < len(plan.furniture) < len(plan.rooms)
    # Every room is reachable by the robot: shrink free space by the robot radius (plus a
    # margin) and it must still be one piece that reaches into every room.
    reachable = world.free_region.buffer(-(ROBOT_RADIUS_M + 0.2))
    assert isinstance(reachable, Polygon)
    for room in plan.rooms:
        assert reachable.intersection(box(*room)).area > 1.0
    # The corridors are free space: no room or furniture intrudes on them.
    corridors = unary_union([box(*c) for c in plan.corridors])
    assert corridors.difference(world.free_region).area < 1e-6


@pytest.mark.parametrize("seed", [0, 7, 123])
def test_maze_plan_is_a_nearly_perfect_maze(worlds, seed):
    plan = maze_plan(seed)
    world = worlds[f"maze:{seed}"]
    assert 2.0 <= plan.cell_m <= 3.0
    assert plan.cell_m - plan.wall_m >= 1.4  # passage width
    n_cells = plan.n * plan.n
    assert len(plan.openings) == n_cells - 1 + len(plan.extra_openings)
    assert 1 <= len(plan.extra_openings) <= n_cells // 20
    # A spanning tree plus k extra openings has exactly k independent cycles, so the free
    # region has exactly k holes (and no free-standing wall posts beyond those).
    assert len(world.free_region.interiors) == len(plan.extra_openings)
    assert world.free_area_m2 == pytest.approx(
        n_cells * (plan.cell_m - plan.wall_m) ** 2
        + len(plan.openings) * plan.wall_m * (plan.cell_m - plan.wall_m)
    )
    post = plan.wall_m**2  # a lone post would be a hole of exactly this area
    assert min(Polygon(r.coords).area for r in world.free_region.interiors) > 2 * post


def test_seed_spellings():
    assert builtin_world("office:007").name == "office:7"
    with pytest.raises(WorldError, match="maze:x: the seed must be a non-negative integer"):
        builtin_world("maze:x")
    with pytest.raises(WorldError, match="valid names are fig1, fig12"):
        builtin_world("fig99")

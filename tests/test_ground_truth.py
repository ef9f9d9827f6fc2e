"""Ground-truth GVG against worlds whose GVG is known in closed form."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from scipy.integrate import quad
from scipy.optimize import brentq
from shapely import affinity
from shapely.geometry import box
from shapely.ops import unary_union

from sim_backend.ground_truth import BENT_WALL_RATIO, GroundTruthGVG, compute_gvg
from sim_backend.world import GridWorld, PolygonWorld, StartPose

SQ2 = math.sqrt(2.0)
CMIN = 0.40
TAU = 2.0 * math.pi


def pointed_corridor(length=10.0, width=2.0, start=None):
    """A corridor whose ends are 90-degree wedges: the centre line runs into the apexes, and
    the 135-degree corners where wedge meets side wall are too flat (45 degrees of
    separation) to grow branches, so the GVG is a single edge."""
    h = width / 2
    boundary = [(0, 0), (length, 0), (length + h, h), (length, width), (0, width), (-h, h)]
    return PolygonWorld("corridor", boundary, [], start or StartPose(length / 2, 0.6 * h))


def tee_world():
    corners = "0,0 10,0 11,1 10,2 6,2 6,8 5,9 4,8 4,2 0,2 -1,1"  # pointed ends, as above
    boundary = [tuple(map(float, c.split(","))) for c in corners.split()]
    return PolygonWorld("tee", boundary, [], StartPose(2.0, 0.8))


def plus_world():
    arm = [(1, -1), (5, -1), (6, 0), (5, 1)]  # one arm, pointing +x, rotated four times
    boundary = []
    for k in range(4):
        c, s = round(math.cos(k * math.pi / 2)), round(math.sin(k * math.pi / 2))
        boundary += [(c * x - s * y, s * x + c * y) for x, y in arm]
    return PolygonWorld("plus", boundary, [], StartPose(-3.0, 0.3))


def ring_world(size=6.0, a=2.0):
    room = [(0, 0), (size, 0), (size, size), (0, size)]
    pillar = [(a, a), (size - a, a), (size - a, size - a), (a, size - a)]
    return PolygonWorld("ring", room, [pillar], StartPose(1.0, 3.0))


def edge_points(gvg: GroundTruthGVG) -> np.ndarray:
    return np.vstack([e.points for e in gvg.edges])


def resample(points: np.ndarray, step: float) -> np.ndarray:
    d = np.hypot(*np.diff(points, axis=0).T)
    cum = np.concatenate([[0.0], np.cumsum(d)])
    s = np.arange(0.0, cum[-1], step)
    return np.column_stack([np.interp(s, cum, points[:, 0]), np.interp(s, cum, points[:, 1])])


def check_graph_consistency(g: GroundTruthGVG) -> None:
    ends = np.zeros(len(g.nodes), dtype=int)
    for e in g.edges:
        ends[e.u] += 1
        ends[e.v] += 1
        assert np.allclose(e.points[0], g.nodes[e.u].xy, atol=1e-9)
        assert np.allclose(e.points[-1], g.nodes[e.v].xy, atol=1e-9)
        assert e.length_m == pytest.approx(np.hypot(*np.diff(e.points, axis=0).T).sum())
    for n in g.nodes:
        assert n.degree == ends[n.id]
        assert len(n.departure_angles) == n.degree
        assert list(n.departure_angles) == sorted(n.departure_angles)
        assert all(0.0 <= a < TAU for a in n.departure_angles)
        assert (n.kind == "meet") == (n.degree >= 3)


# ----------------------------------------------------------------------------------------


def test_pointed_corridor_is_one_centre_line_edge():
    g = compute_gvg(pointed_corridor())
    check_graph_consistency(g)
    assert len(g.edges) == 1 and not g.meet_points
    pts = edge_points(g)
    assert np.abs(pts[:, 1] - 1.0).max() < 0.01
    # Boundary points where the clearance to the wedge walls, (x + 1) / sqrt 2, is 0.40.
    x_end = CMIN * SQ2 - 1.0
    ends = sorted(g.boundary_points, key=lambda n: n.x)
    assert [n.reason for n in ends] == ["clearance", "clearance"]
    assert ends[0].x == pytest.approx(x_end, abs=0.01)
    assert ends[1].x == pytest.approx(10.0 - x_end, abs=0.01)
    assert all(n.clearance_m == pytest.approx(CMIN, abs=0.002) for n in ends)
    assert g.gvg_length_m == pytest.approx(10.0 - 2 * x_end, abs=0.01)
    assert g.other_components == 0


def test_rectangular_corridor_ends_in_corner_branches():
    """Flat ends: at each end a meet point w/2 in, with two branches into the corners that
    stop where the clearance falls to 0.40 (on the corner bisector, at (0.4, 0.4))."""
    world = PolygonWorld("rect", [(0, 0), (10, 0), (10, 2), (0, 2)], [], StartPose(5, 0.5))
    g = compute_gvg(world)
    check_graph_consistency(g)
    meets = sorted(g.meet_points, key=lambda n: n.x)
    assert [m.degree for m in meets] == [3, 3]
    assert meets[0].x == pytest.approx(1.0, abs=0.02) and meets[0].y == pytest.approx(1.0, abs=0.02)
    assert meets[1].x == pytest.approx(9.0, abs=0.02)
    assert all(m.clearance_m == pytest.approx(1.0, abs=0.01) for m in meets)
    corners = {(round(n.x, 2), round(n.y, 2)) for n in g.boundary_points}
    assert corners == {(0.4, 0.4), (0.4, 1.6), (9.6, 0.4), (9.6, 1.6)}
    assert g.gvg_length_m == pytest.approx(8.0 + 4 * (1.0 - CMIN) * SQ2, abs=0.02)


def test_tee_junction_meet_point_and_departure_angles():
    g = compute_gvg(tee_world())
    check_graph_consistency(g)
    (m,) = g.meet_points
    # Equidistant to the floor y = 0 and the two convex corners (4, 2), (6, 2).
    assert m.degree == 3
    assert m.x == pytest.approx(5.0, abs=0.02) and m.y == pytest.approx(1.25, abs=0.02)
    assert m.clearance_m == pytest.approx(1.25, abs=0.01)
    assert len(g.boundary_points) == 3 and len(g.edges) == 3

    # The left edge leaves on the parabola y = ((x - 4)^2 + 4) / 4 (floor vs corner (4, 2)).
    def arc(x: float) -> float:
        return quad(lambda s: math.sqrt(1 + ((s - 4) / 2) ** 2), x, 5.0)[0]

    x = brentq(lambda x: arc(x) - g.departure_distance_m, 4.0, 5.0)
    left = math.atan2(((x - 4) ** 2 + 4) / 4 - 1.25, x - 5.0) % TAU
    right = (math.pi - left) % TAU
    assert np.allclose(m.departure_angles, [math.pi / 2, left, right], atol=0.01)


def test_plus_junction_is_one_degree_four_meet_point():
    g = compute_gvg(plus_world())
    check_graph_consistency(g)
    assert len(g.meet_points) == 1
    (m,) = g.meet_points
    assert m.degree == 4
    assert math.hypot(m.x, m.y) < 0.02
    assert m.clearance_m == pytest.approx(SQ2, abs=0.01)
    assert np.allclose(m.departure_angles, [0, math.pi / 2, math.pi, 3 * math.pi / 2], atol=0.01)
    assert len(g.boundary_points) == 4


def test_room_with_pillar_has_one_cycle_and_corner_boundaries():
    size, a = 6.0, 2.0
    g = compute_gvg(ring_world(size, a))
    check_graph_consistency(g)
    # One independent cycle: E - V + 1.
    assert len(g.edges) - len(g.nodes) + 1 == 1
    t = a * (2 - SQ2)  # on the diagonal: t = distance to both walls = distance to the corner
    meets = g.meet_points
    assert [m.degree for m in meets] == [3, 3, 3, 3]
    for m in meets:
        assert min(abs(m.x - t), abs(m.x - (size - t))) < 0.02
        assert min(abs(m.y - t), abs(m.y - (size - t))) < 0.02
        assert m.clearance_m == pytest.approx(t, abs=0.01)
    corner_pts = {(0.4, 0.4), (0.4, 5.6), (5.6, 0.4), (5.6, 5.6)}
    assert {(round(n.x, 2), round(n.y, 2)) for n in g.boundary_points} == corner_pts
    for b in g.boundary_points:
        assert b.clearance_m == pytest.approx(CMIN, abs=0.002)
        assert b.reason == "clearance"
        # Its edge heads diagonally back into the room, away from its corner.
        cx, cy = round(b.x / size) * size, round(b.y / size) * size
        away = math.atan2(b.y - cy, b.x - cx) % TAU
        assert b.departure_angles[0] == pytest.approx(away, abs=0.01)
    # Loop length: four straight mid-lines plus eight parabolic arcs x = (a^2 + (y-a)^2)/2a.
    arc = quad(lambda y: math.sqrt(1 + ((y - a) / a) ** 2), t, a)[0]
    spur = (t - CMIN) * SQ2
    assert g.gvg_length_m == pytest.approx(4 * (size - 2 * a) + 8 * arc + 4 * spur, abs=0.02)


def test_room_beyond_sonar_range_is_cut_at_the_horizon():
    world = PolygonWorld("hall", [(0, 0), (30, 0), (30, 20), (0, 20)], [], StartPose(2.0, 1.5))
    g = compute_gvg(world)
    check_graph_consistency(g)
    # The start's piece is the corner diagonal, from the corner boundary to the horizon.
    (b,) = g.boundary_points
    (h,) = g.horizon_points
    assert (b.x, b.y) == pytest.approx((CMIN, CMIN), abs=0.01)
    assert h.kind == "horizon" and h.reason == "range"
    assert (h.x, h.y) == pytest.approx((6.73, 6.73), abs=0.01)
    assert h.clearance_m == pytest.approx(g.max_clearance_m, abs=0.01)
    assert g.gvg_length_m == pytest.approx((6.73 - CMIN) * SQ2, abs=0.01)
    assert g.other_components == 3  # the other three corner diagonals
    # With an unlimited horizon the hall's GVG is whole again: two meet points, one piece.
    whole = compute_gvg(world, max_clearance_m=20.0)
    assert whole.other_components == 0 and not whole.horizon_points
    assert sorted((round(m.x, 2), round(m.y, 2)) for m in whole.meet_points) == [
        (10.0, 10.0),
        (20.0, 10.0),
    ]


def test_two_disconnected_free_regions():
    wall = [(4.5, -1), (5.5, -1), (5.5, 5), (4.5, 5)]  # crosses the boundary: two rooms
    world = PolygonWorld("split", [(0, 0), (10, 0), (10, 4), (0, 4)], [wall], StartPose(1, 1))
    g = compute_gvg(world)
    check_graph_consistency(g)
    assert g.other_components == 1
    assert all(n.x < 4.5 for n in g.nodes)
    assert [m.degree for m in g.meet_points] == [3, 3]


def test_door_edge_runs_through_into_both_rooms():
    """A 1 m door in a wall between two rooms: the jambs are two obstacles at any angle (the
    wall joins them only the long way round), so the door's edge continues until it meets
    each room's own GVG and the two rooms form one graph, as the paper's robot found when it
    left the lab through an open door (Fig. 14)."""
    wall = [(0, 6), (3.5, 6), (3.5, 6.2), (0, 6.2)], [(4.5, 6), (8, 6), (8, 6.2), (4.5, 6.2)]
    world = PolygonWorld(
        "door", [(0, 0), (8, 0), (8, 12.2), (0, 12.2)], list(wall), StartPose(4.0, 6.1)
    )
    g = compute_gvg(world)
    check_graph_consistency(g)
    assert g.other_components == 0
    assert not [n for n in g.boundary_points if n.reason == "separation"]
    assert g.distance_to(np.array([[4.0, 6.1]]))[0] < 1e-3
    (door,) = [
        e for e in g.edges if np.hypot(*(resample(e.points, 0.01) - [4.0, 6.1]).T).min() < 0.01
    ]
    ends = sorted([g.node(door.u), g.node(door.v)], key=lambda n: n.y)
    # The edge runs along the jambs' bisector into each room and ends at a meet point there.
    assert all(n.kind == "meet" for n in ends)
    assert ends[0].y < 6.0 - 1.0 and ends[1].y > 6.2 + 1.0
    assert np.abs(door.points[:, 0] - 4.0).max() < 0.01
    assert len(g.meet_points) >= 2 and {m.y < 6.1 for m in g.meet_points} == {True, False}


def test_grid_corridor_staircase_makes_no_spurious_meet_points():
    res, width, length, ang = 0.05, 1.6, 10.0, math.radians(30.0)
    n = int(14 / res)
    ys, xs = np.mgrid[0:n, 0:n]
    px, py = (xs + 0.5) * res - 2.0, (ys + 0.5) * res - 2.0
    along = px * math.cos(ang) + py * math.sin(ang)
    across = -px * math.sin(ang) + py * math.cos(ang)
    occupied = ~((along > 0) & (along < length) & (np.abs(across) < width / 2))
    start = StartPose(2 + 3 * math.cos(ang), 2 + 3 * math.sin(ang))
    world = GridWorld("grid-corridor", occupied, res, (0.0, 0.0), start)
    g = compute_gvg(world)
    check_graph_consistency(g)
    # Only the two flat (rasterised) ends have meet points, w/2 in from each end.
    assert len(g.meet_points) == 2 and all(m.degree == 3 for m in g.meet_points)
    for m in g.meet_points:
        a = (m.x - 2) * math.cos(ang) + (m.y - 2) * math.sin(ang)
        assert min(abs(a - width / 2), abs(a - (length - width / 2))) < 0.1
    (main,) = [e for e in g.edges if e.length_m > 2.0]
    assert main.length_m == pytest.approx(length - width, abs=0.1)
    off = -(main.points[:, 0] - 2) * math.sin(ang) + (main.points[:, 1] - 2) * math.cos(ang)
    assert np.abs(off).max() < res  # the cells shift the walls by under one cell
    assert g.other_components == 0


def test_flat_bend_grows_no_spur():
    """A 170-degree bend in one wall: its medial-axis spur sees the two wall pieces only
    10 degrees apart, one obstacle to the sonar ring."""
    ang = math.radians(10.0)
    x2, y2 = 5 + 5 * math.cos(ang), 5 * math.sin(ang)
    boundary = [(0, 0), (5, 0), (x2, y2), (x2 + 1, y2 + 1.5), (x2, 3), (0, 3), (-1.5, 1.5)]
    world = PolygonWorld("bend", boundary, [], StartPose(2.0, 1.0))
    g = compute_gvg(world)
    check_graph_consistency(g)
    assert not g.meet_points and len(g.edges) == 1
    # The spur is really there in the medial axis: drop the separation rule to see it.
    bare = compute_gvg(world, min_separation_deg=5.0)
    assert any(abs(m.x - 5.0) < 0.5 and m.degree == 3 for m in bare.meet_points)


def test_cycle_without_meet_points_gets_a_loop_node():
    ang = np.linspace(0, TAU, 48, endpoint=False)
    ring = np.column_stack([np.cos(ang), np.sin(ang)])
    world = PolygonWorld("annulus", 8 + 7 * ring, [8 + 2 * ring], StartPose(8.0, 3.5))
    g = compute_gvg(world)
    check_graph_consistency(g)
    (node,) = g.nodes
    (edge,) = g.edges
    assert node.kind == "loop" and node.degree == 2 and edge.u == edge.v == node.id
    mid_apothem = 4.5 * math.cos(math.pi / 48)
    assert g.gvg_length_m == pytest.approx(TAU * mid_apothem, rel=0.01)
    r = np.hypot(*(edge.points - 8.0).T)
    assert r.min() > 4.3 and r.max() < 4.6


def test_distance_to_on_and_off_the_gvg():
    g = compute_gvg(pointed_corridor())
    on = resample(edge_points(g), 0.037)
    assert g.distance_to(on).max() < 1e-6
    x_end = CMIN * SQ2 - 1.0
    off = np.array([[5.0, 1.3], [5.0, 0.5], [x_end - 0.3, 1.0], [x_end - 0.3, 1.4]])
    got = g.distance_to(off)
    assert got[:2] == pytest.approx([0.3, 0.5], abs=1e-6)
    assert got[2:] == pytest.approx([0.3, 0.5], abs=1e-3)  # past the end node (sampled)
    assert g.distance_to(np.zeros((0, 2))).shape == (0,)
    # Matches brute force over the polylines on scattered points.
    rng = np.random.default_rng(7)
    ring = compute_gvg(ring_world())
    pts = rng.uniform(-1, 7, size=(2000, 2))
    segs = np.vstack([np.hstack([e.points[:-1], e.points[1:]]) for e in ring.edges])
    a, d = segs[:, :2], segs[:, 2:] - segs[:, :2]
    t = np.clip(((pts[:, None] - a) * d).sum(-1) / (d * d).sum(-1), 0, 1)
    brute = np.hypot(*(pts[:, None] - (a + t[..., None] * d)).transpose(2, 0, 1)).min(axis=1)
    assert np.allclose(ring.distance_to(pts), brute, atol=1e-9)


def test_nearest_node_and_json_export():
    g = compute_gvg(ring_world())
    m = g.nearest_node(0.0, 0.0, kind="meet")
    assert m is not None and m.kind == "meet" and m.x < 3 and m.y < 3
    b = g.nearest_node(0.0, 0.0)
    assert b is not None and b.kind == "boundary"
    assert g.nearest_node(0.0, 0.0, kind="horizon") is None
    with pytest.raises(ValueError):
        g.nearest_node(0.0, 0.0, kind="junction")
    d = json.loads(json.dumps(g.to_dict()))
    assert len(d["nodes"]) == len(g.nodes) and len(d["edges"]) == len(g.edges)
    assert d["nodes"][0]["kind"] == "meet" and d["nodes"][0]["degree"] == 3
    e0 = d["edges"][0]
    assert e0["points"][0] == [round(g.nodes[e0["u"]].x, 3), round(g.nodes[e0["u"]].y, 3)]
    assert d["parameters"]["min_clearance_m"] == CMIN


def test_invalid_parameters_are_rejected():
    world = pointed_corridor()
    for kwargs in (
        {"min_separation_deg": 0.0},
        {"min_clearance_m": 7.0},
        {"sample_spacing_m": 0.0},
        {"min_branch_m": -1.0},
    ):
        with pytest.raises(ValueError):
            compute_gvg(world, **kwargs)


def _cluttered_world(seed: int, size: float = 13.0) -> PolygonWorld:
    rng = np.random.default_rng(seed)
    boxes = []
    for _ in range(12):
        cx, cy = rng.uniform(1.5, size - 1.5, 2)
        w, h = rng.uniform(0.3, 1.6, 2)
        boxes.append(
            affinity.rotate(
                box(cx - w / 2, cy - h / 2, cx + w / 2, cy + h / 2), rng.uniform(0, 180)
            )
        )
    merged = unary_union(boxes)
    polys = getattr(merged, "geoms", [merged])
    obstacles = [np.asarray(p.exterior.coords)[:-1] for p in polys]
    room = [(0, 0), (size, 0), (size, size), (0, size)]
    return PolygonWorld(f"clutter-{seed}", room, obstacles, StartPose(0.8, 0.8))


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_every_gvg_point_is_equidistant_to_two_separated_walls(seed):
    """The defining property, checked against the exact wall geometry: each point of each
    edge has its nearest wall point and another at the same distance (within 3 mm) that is a
    separate obstacle (~min_separation away in bearing, or joined to the first only the long
    way round along the wall); meet points have three."""
    world = _cluttered_world(seed)
    g = compute_gvg(world, merge_meet_m=0.0)  # the exact medial axis, no resolution merge
    check_graph_consistency(g)
    assert len(g.meet_points) >= 3
    segs = world.segments
    a, d = segs[:, :2], segs[:, 2:] - segs[:, :2]

    def feet(x):
        t = np.clip(((x - a) * d).sum(1) / (d * d).sum(1), 0, 1)
        q = a + t[:, None] * d
        return q - x, np.hypot(*(q - x).T)

    cos_sep = math.cos(math.radians(g.min_separation_deg - 3.0))
    arcs = world.wall_arcs
    lengths = np.hypot(d[:, 0], d[:, 1])
    for e in g.edges:
        for x in resample(e.points, 0.05)[1:]:
            v, dist = feet(x)
            i = int(np.argmin(dist))
            cos = (v @ v[i]) / (dist * dist[i])
            # Another wall point as near: well apart in bearing, or one that the wall joins
            # to the nearest only the long way round.
            t = np.clip(((x - a) * d).sum(1) / (d * d).sum(1), 0, 1)
            s_arc = arcs.position(np.arange(len(segs)), t, lengths)
            along = arcs.along_wall(arcs.chain[i], s_arc[i], arcs.chain, s_arc)
            chord = np.hypot(*(v - v[i]).T)
            two = (cos <= cos_sep) | (along > BENT_WALL_RATIO * chord + 1e-9)
            d2 = dist[two].min()
            assert d2 - dist[i] < 0.003
            assert g.min_clearance_m - 0.002 < dist[i] < g.max_clearance_m + 0.002
    for m in g.meet_points:
        v, dist = feet(m.xy)
        assert m.clearance_m == pytest.approx(dist.min(), abs=1e-6)
        bearings = np.sort(np.arctan2(v[:, 1], v[:, 0])[dist < dist.min() + 0.001])
        gaps = np.diff(np.concatenate([bearings, [bearings[0] + TAU]]))
        assert (gaps > math.radians(10)).sum() >= 3


def test_medium_world_is_fast():
    g = compute_gvg(_cluttered_world(4))  # 169 m2
    assert g.compute_time_s < 5.0
    assert g.gvg_length_m > 10.0


def test_meet_points_closer_than_the_robot_are_one_place():
    """Junctions 0.2 m apart are one meet point when merging at the robot's diameter is asked
    for, carrying all the outer edges, and two by default."""
    from sim_backend.world_files import load_world

    world = load_world("fig1")
    exact = compute_gvg(world)
    merged = compute_gvg(world, merge_meet_m=0.46)
    check_graph_consistency(merged)
    m = np.array([[n.x, n.y] for n in exact.meet_points])
    d = np.hypot(*(m[:, None, :] - m[None, :, :]).transpose(2, 0, 1))
    np.fill_diagonal(d, np.inf)
    close_pairs = int((d < merged.merge_meet_m).sum()) // 2
    assert close_pairs >= 1
    assert len(merged.meet_points) == len(exact.meet_points) - close_pairs
    degree_sum = sum(n.degree for n in exact.meet_points) - 2 * close_pairs
    assert sum(n.degree for n in merged.meet_points) == degree_sum

"""A grid map's walls as the building has them: ragged cells and staircases straightened."""

from __future__ import annotations

import math

import numpy as np
import pytest

from hal.types import Twist
from sim_backend.backend import SimBackend
from sim_backend.grid_walls import boundary_rings, grid_walls, wall_tolerance
from sim_backend.ground_truth import compute_gvg
from sim_backend.simulator import SimParams
from sim_backend.world import GridWorld, PolygonWorld, StartPose

RES = 0.05
EXACT = SimParams(sonar_noise=False, drift="none", side_lobe_prob=0.0)


def office(ragged: float, seed: int = 3) -> np.ndarray:
    """A 9 x 6 m room with a cabinet and a 1 m door to a 2 m corridor; ``ragged``: the share
    of cells on either side of every wall flipped, as a SLAM map draws walls."""
    ny, nx = int(6.0 / RES), int(9.0 / RES)
    occ = np.zeros((ny, nx), bool)

    def box(x0: float, y0: float, x1: float, y1: float, value: bool = True) -> None:
        occ[round(y0 / RES) : round(y1 / RES), round(x0 / RES) : round(x1 / RES)] = value

    box(0, 0, 9, 0.2)
    box(0, 5.8, 9, 6)
    box(0, 0, 0.2, 6)
    box(8.8, 0, 9, 6)
    box(0, 3.6, 9, 3.8)  # the corridor's wall
    box(3.5, 3.6, 4.5, 3.8, False)  # its door
    box(6.0, 1.0, 7.0, 1.6)  # a cabinet
    edge = (occ != np.roll(occ, 1, 0)) | (occ != np.roll(occ, 1, 1))
    rng = np.random.default_rng(seed)
    return occ ^ (edge & (rng.random(occ.shape) < ragged))


def world_of(occ: np.ndarray) -> GridWorld:
    return GridWorld("office", occ, RES, (0.0, 0.0), StartPose(2.0, 2.0, 0.0))


def test_a_ragged_wall_is_one_straight_wall():
    world = world_of(office(0.15))
    segs = world.segments
    # The corridor wall's room side, y = 3.6 between the west wall and the door: one or two
    # segments within a cell of the line, against some forty cell edges unstraightened.
    on = [
        s
        for s in segs
        if max(abs(s[1] - 3.6), abs(s[3] - 3.6)) < 0.1 and min(s[0], s[2]) < 3.0
    ]
    assert 1 <= len(on) <= 3
    assert sum(math.hypot(s[2] - s[0], s[3] - s[1]) for s in on) > 3.0
    for s in on:
        assert abs(s[1] - 3.6) <= RES + 1e-9 and abs(s[3] - 3.6) <= RES + 1e-9
    # No corner along it: the sonar hears a wall there, not a row of reflectors.
    c = world.corners
    assert not ((c[:, 0] > 0.6) & (c[:, 0] < 3.2) & (np.abs(c[:, 1] - 3.6) < 0.1)).any()
    raw = grid_walls(world.occupied, RES, (0.0, 0.0), 0.0)[0]
    assert len(raw) > 5 * len(segs)


def test_a_ragged_map_has_the_ground_truth_of_its_clean_one():
    clean = compute_gvg(world_of(office(0.0)))
    ragged = compute_gvg(world_of(office(0.15)))
    assert len(clean.meet_points) >= 4
    assert len(ragged.meet_points) == len(clean.meet_points)
    for m in clean.meet_points:
        n = ragged.nearest_node(m.x, m.y, kind="meet")
        assert n is not None and math.hypot(n.x - m.x, n.y - m.y) < 0.1
        assert n.degree == m.degree
    assert ragged.gvg_length_m == pytest.approx(clean.gvg_length_m, rel=0.03)


def test_the_sonar_reads_a_ragged_wall_as_the_clean_one():
    def ranges(occ: np.ndarray) -> np.ndarray:
        b = SimBackend(world_of(occ), EXACT, 1)
        with b:
            b.command(Twist(0.0, 0.0, 0.0))
            b.clock.sleep(1.0)
            return np.array(b.scan().ranges_m)

    clean, ragged = ranges(office(0.0)), ranges(office(0.15))
    heard = np.isfinite(clean)
    assert heard.sum() >= 8
    assert np.array_equal(np.isfinite(ragged), heard)
    assert np.abs(ragged[heard] - clean[heard]).max() < 2 * RES


def test_a_coarse_grid_keeps_its_steps():
    # 0.5 m cells: a staircase is the world's shape, not a map's noise.
    occ = np.ones((8, 8), bool)
    for k in range(1, 7):
        occ[1 : k + 1, k] = False
    world = GridWorld("steps", occ, 0.5, (0.0, 0.0), StartPose(3.25, 0.75, 0.0))
    assert wall_tolerance(0.5) < 0.5
    xs = world.segments[:, [0, 2]].ravel()
    ys = world.segments[:, [1, 3]].ravel()
    assert np.allclose(xs / 0.5, np.round(xs / 0.5)) and np.allclose(ys / 0.5, np.round(ys / 0.5))
    # Every step is a corner: six risers, each with a convex and a concave corner, less the ends.
    assert len(world.corners) >= 12


def test_cells_touching_at_a_corner_are_one_obstacle():
    occ = np.zeros((10, 10), bool)
    occ[4, 4] = occ[5, 5] = True
    rings = boundary_rings(occ)
    # The grid's border (outside counts as occupied) and one ring round both cells.
    assert len(rings) == 2
    (inner,) = [r for r in rings if r.min() > 0]
    assert {(4, 4), (6, 6)} <= {tuple(p) for p in inner.tolist()}
    assert [tuple(p) for p in inner.tolist()].count((5, 5)) == 2  # through the pinch twice


def test_a_notch_a_few_centimetres_deep_grows_no_spur():
    """The ground truth's separation rule: a 5 cm notch in a wall is one wall to the ring."""
    room = [(0, 0), (6, 0), (6, 4), (0, 4)]
    notched = [(0, 0), (3.0, 0), (3.0, 0.05), (3.05, 0.05), (3.05, 0), (6, 0), (6, 4), (0, 4)]
    start = StartPose(1.5, 2.0, 0.0)
    plain = compute_gvg(PolygonWorld("room", room, [], start))
    notch = compute_gvg(PolygonWorld("notch", notched, [], start))
    assert len(notch.meet_points) == len(plain.meet_points)
    assert len(notch.edges) == len(plain.edges)

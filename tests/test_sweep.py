"""The turret sweep at a standstill: Fig. 4's rules on a dense circular array, the bent-wall
merge, and the sweep run on the simulated robot where the ring alone misreads bearings."""

from __future__ import annotations

import math

import numpy as np
import pytest

from hal.registry import create_backend
from hal.types import SonarScan, Twist
from sim_backend.backend import SimBackend
from sim_backend.builtin_worlds import builtin_world
from sim_backend.ground_truth import compute_gvg
from sim_backend.world import PolygonWorld, StartPose
from tests.tracer_paths import GIVING_UP
from tslam.core import sweep as sweep_module
from tslam.core.sweep import DENSE_BINS, WIDE_BEND_MERGE_RAD, Sweep, sweep_minima
from tslam.core.tracer import MeetPointReached, Tracer, TracerParams
from tslam.programs.trace_cmd import run_trace


def _ring(step_deg: float = 5.0) -> np.ndarray:
    return np.radians(np.arange(0.0, 360.0, step_deg))


def _bearings(obs) -> list[float]:
    return sorted(round(math.degrees(o.bearing_rad) % 360.0) for o in obs)


def test_a_plateau_is_one_obstacle_at_its_middle():
    b = _ring()
    d = np.full(len(b), np.inf)
    d[(b >= math.radians(80)) & (b <= math.radians(110))] = 1.0  # a wall heard over 30 deg
    obs = sweep_minima(b, d)
    assert len(obs) == 1
    assert math.degrees(obs[0].bearing_rad) == pytest.approx(95.0)
    assert obs[0].distance_m == 1.0
    away = (-math.cos(math.radians(95)), -math.sin(math.radians(95)))
    assert (obs[0].gx, obs[0].gy) == pytest.approx(away)


def test_a_slope_next_to_a_lower_run_is_not_an_obstacle():
    b = _ring()
    deg = np.degrees(b)
    d = np.full(len(b), np.inf)
    d[(deg >= 80) & (deg <= 100)] = 1.0
    d[(deg > 100) & (deg <= 140)] = 1.0 + 0.02 * (deg[(deg > 100) & (deg <= 140)] - 100)
    assert _bearings(sweep_minima(b, d)) == [90]


def test_stray_echoes_shorter_than_the_beam_are_ignored():
    b = _ring()
    d = np.full(len(b), np.inf)
    d[18] = 0.8  # one sample: a side lobe or multipath
    d[(b >= math.radians(200)) & (b <= math.radians(225))] = 1.2
    assert _bearings(sweep_minima(b, d)) == [212]


def test_door_jambs_close_in_bearing_stay_two_obstacles():
    # Two jamb corners 40 deg apart with the corridor behind the door seen between them.
    b = _ring()
    deg = np.degrees(b)
    d = np.full(len(b), np.inf)
    d[(deg >= 330) & (deg <= 350)] = 1.4
    d[(deg > 350) | (deg < 10)] = 3.7
    d[(deg >= 10) & (deg <= 30)] = 1.4
    assert _bearings(sweep_minima(b, d)) == [20, 340]


def test_one_bent_wall_close_in_bearing_is_one_obstacle():
    # Two faces of a flat concave bend, 40 deg apart, the bend's vertex slightly farther.
    b = _ring()
    deg = np.degrees(b)
    d = np.full(len(b), np.inf)
    d[(deg >= 330) & (deg <= 350)] = 1.40
    d[(deg > 350) | (deg < 10)] = 1.52
    d[(deg >= 10) & (deg <= 30)] = 1.42
    obs = sweep_minima(b, d)
    assert len(obs) == 1 and round(math.degrees(obs[0].bearing_rad) % 360) == 340
    # Far apart in bearing, the same two faces are two obstacles.
    d2 = np.full(len(b), np.inf)
    d2[(deg >= 300) & (deg <= 320)] = 1.40
    d2[(deg >= 40) & (deg <= 60)] = 1.42
    assert len(sweep_minima(b, d2)) == 2


def test_no_echo_anywhere_is_no_obstacle():
    b = _ring()
    assert sweep_minima(b, np.full(len(b), np.inf)) == []


def test_the_sweep_on_the_robot_finds_four_door_and_wall_obstacles_at_fig14s_junction():
    # Fig. 14's degree-4 meet point by the lab's right door: a wall, two jambs 41 deg apart
    # and a table corner, all 1.41 m away. From any heading the sweep finds all four.
    fig14 = builtin_world("fig14")
    for heading_deg in (0, 50, 130, 250):
        start = StartPose(9.18, 6.09, math.radians(heading_deg))
        world = PolygonWorld("fig14", fig14.boundary, fig14.obstacles, start, source="test")
        backend = SimBackend(world, seed=heading_deg)
        with backend:
            sweep = Sweep(start_s=backend.clock.now())
            backend.command(Twist(0.0, 0.0, math.radians(22.5) / 3.9))
            while backend.clock.now() < 3.9:
                backend.clock.sleep(0.1)
                sweep.add(backend.scan())
        near = [o for o in sweep.obstacles() if o.distance_m < 1.55]
        world_bearings = sorted(
            (math.degrees(o.bearing_rad) + heading_deg) % 360.0 for o in near
        )
        assert len(near) == 4, (heading_deg, world_bearings)
        for got, want in zip(world_bearings, (21.0, 90.0, 231.0, 340.0), strict=True):
            assert abs(got - want) < 8.0, (heading_deg, world_bearings)


def _fine_ring() -> np.ndarray:
    """A ring that fires all its transducers within 100 ms, swept: some 700 readings."""
    return _ring(0.5)


def test_a_fast_rings_side_lobe_streaks_are_not_obstacles():
    # A wall answers the side lobes at its own distance, half the firings, for 17.5 degrees
    # either side of its plateau (a specular sonar hears a flat wall only from the foot of
    # the perpendicular: ``sim_backend/kernels.py``). On a fast ring the streaks' pieces are
    # many readings long; they are not walls of their own, nor is the wall's bearing theirs.
    rng = np.random.default_rng(7)
    b = _fine_ring()
    off = np.abs(np.degrees(b) - 95.0)
    d = np.full(len(b), np.inf)
    d[off <= 30.0] = 1.0 + rng.normal(0.0, 0.02, int((off <= 30.0).sum()))
    lobe = (off > 12.5) & (off <= 30.0)
    d[lobe & (rng.random(len(b)) < 0.5)] = np.inf
    (wall,) = sweep_minima(b, d)
    assert abs(math.degrees(wall.bearing_rad) - 95.0) <= 5.0
    # A slow ring's sweep holds a wall in three samples: still an obstacle.
    slow = _ring(5.6)
    ds = np.full(len(slow), np.inf)
    ds[(np.degrees(slow) >= 190) & (np.degrees(slow) <= 202)] = 1.1
    assert _bearings(sweep_minima(slow, ds)) == [196]


def test_stray_deep_readings_do_not_split_a_bent_wall_on_a_fast_ring():
    b = _fine_ring()
    deg = np.degrees(b)
    d = np.full(len(b), np.inf)
    d[(deg >= 330) & (deg <= 350)] = 1.40
    d[(deg > 350) | (deg < 10)] = 1.52
    d[(deg >= 10) & (deg <= 30)] = 1.42
    d[np.flatnonzero((deg > 355) | (deg < 5))[[2, 9, 15]]] = 5.2  # three outliers
    assert len(sweep_minima(b, d)) == 1
    # A view past the bend some degrees wide (a doorway) still makes two.
    d[(deg > 356) | (deg < 4)] = 3.7
    assert len(sweep_minima(b, d)) == 2


def _dense_junction(seed: int) -> tuple[np.ndarray, np.ndarray]:
    """A fast ring's sweep at a junction (about 700 readings), as the simulated sonar gives
    it: three walls 1.36-1.42 m off, each answering the main beam over the 25 degrees of
    axis that hold its normal (2 % dropped out) and the side lobes 17.5 degrees either side
    of that half the time, with 1 cm + 1 % of noise; the rooms' far walls 4 m off between."""
    rng = np.random.default_rng(seed)
    b = _fine_ring()
    deg = np.degrees(b)
    d = np.full(len(b), 4.0)
    answers = np.ones(len(b))
    for normal, dist in ((47.5, 1.40), (167.5, 1.36), (287.5, 1.42)):
        off = np.abs((deg - normal + 180.0) % 360.0 - 180.0)
        d[off <= 30.0] = dist
        answers[off <= 30.0] = np.where(off[off <= 30.0] <= 12.5, 0.98, 0.5)
    d = d + rng.normal(0.0, 1.0, len(d)) * (0.01 + 0.01 * d)
    d[rng.random(len(d)) > answers] = np.inf
    return b, d


def _near_walls(obs) -> list[float]:
    return sorted(round(math.degrees(o.bearing_rad) % 360.0) for o in obs if o.distance_m < 2.0)


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_a_dense_sweep_keeps_a_junctions_walls_through_noise_and_dropouts(seed):
    # Hundreds of readings: the lowest is some 3.5 deviations low, and readings as many high
    # broke the plateau from it; the side lobes' dropouts cut the rest into pieces.
    b, d = _dense_junction(seed)
    walls = _near_walls(sweep_minima(b, d))
    assert len(walls) == 3, walls
    for got, want in zip(walls, (47.5, 167.5, 287.5), strict=True):
        assert abs(got - want) <= 5.0, walls


def test_a_dense_sweep_keeps_a_wall_with_a_stray_echo_amid_it():
    # fig12 seed 4 at a 4 ms firing interval: one echo 0.41 m amid a 1.3 m wall made the
    # wall two slopes either side of it, and the junction's sweep found two walls.
    b, d = _dense_junction(1)
    deg = np.degrees(b)
    d[np.flatnonzero((deg >= 165) & (deg <= 166))] = 0.41
    walls = _near_walls(sweep_minima(b, d))
    assert len(walls) == 3 and abs(walls[1] - 167.5) <= 5.0, walls


def test_a_dense_sweep_reads_a_shallow_bend_as_one_wall():
    # fig12's cut corner from a fast ring: the two faces of its 45-degree bend read 71
    # degrees apart, the readings between no deeper than the bend's vertex, and with the
    # block's corner behind they made a meet point the robot swept for minutes.
    rng = np.random.default_rng(4)
    b = _fine_ring()
    deg = np.degrees(b)
    d = np.full(len(b), 4.1)
    d[(deg >= 36) & (deg <= 66)] = 1.36
    between = (deg > 66) & (deg < 107)
    d[between] = 1.36 + 0.14 * np.sin(np.pi * (deg[between] - 66) / 41)
    d[(deg >= 107) & (deg <= 137)] = 1.41
    d[(deg >= 220) & (deg <= 250)] = 1.40
    d = d + rng.normal(0.0, 1.0, len(d)) * (0.01 + 0.01 * d)
    assert len(_near_walls(sweep_minima(b, d))) == 2
    # A door's view between the faces, some degrees wide, still parts them.
    d[(deg >= 84) & (deg <= 90)] = 3.7
    assert len(_near_walls(sweep_minima(b, d))) == 3


def _bent_wall_with_an_outlier(step_deg: float) -> tuple[np.ndarray, np.ndarray]:
    """A concave bend's two faces 1.40 and 1.42 m off, its vertex between them, and one
    outlier at the vertex: fig12's cut corner."""
    b = _ring(step_deg)
    deg = np.degrees(b)
    d = np.full(len(b), np.inf)
    d[(deg >= 330) & (deg <= 350)] = 1.40
    d[(deg > 350) | (deg < 10)] = 1.52
    d[(deg >= 10) & (deg <= 30)] = 1.42
    d[np.argmin(np.abs(deg - 0.0))] = 5.3
    return b, d


def test_one_stray_reading_between_the_faces_of_a_bent_wall_does_not_split_it():
    """fig12's cut corner on a Nomad ring: a single outlier past the bend between the cut
    face and the side wall made them two obstacles, and with the block opposite, a meet point
    4.7 m from any true one. A view into a doorway spans degrees and still separates."""
    b, d = _bent_wall_with_an_outlier(5.6)
    assert len(sweep_minima(b, d)) == 1
    deg = np.degrees(b)
    d[(deg > 354) | (deg < 6)] = 3.7  # a doorway, two readings wide
    assert len(sweep_minima(b, d)) == 2


def test_two_strays_at_unlike_ranges_between_a_bent_walls_faces_are_no_view():
    """fig12 seed 76, its cut corner swept twice: 2.1 m and 5.7 m amid the faces' 1.4 m, 10
    degrees apart, split the bend into two walls and made a meet point that is not there
    (the building was mapped again). A doorway's readings all meet the wall beyond it, at
    about one range: read with ``agree``, only those are a view."""
    b, d = _bent_wall_with_an_outlier(2.8)
    deg = np.degrees(b)
    d[np.argmin(np.abs(deg - 0.0))] = 2.1
    d[np.argmin(np.abs(deg - 8.4))] = 5.7
    assert len(sweep_minima(b, d)) == 2
    assert len(sweep_minima(b, d, agree=True)) == 1
    d[np.argmin(np.abs(deg - 2.8))] = 2.2  # a third, as far as the first: a view
    assert len(sweep_minima(b, d, agree=True)) == 2
    b, d = _bent_wall_with_an_outlier(2.8)
    view = (deg > 354) | (deg < 6)
    d[view] = np.linspace(3.6, 3.8, np.count_nonzero(view))  # a doorway, readings agreeing
    assert len(sweep_minima(b, d, agree=True)) == 2


def test_a_fast_rings_sector_medians_keep_every_deeper_reading_a_view():
    """A fast ring's sweep is read as sector medians, which are no strays: ``agree`` is off
    there, and deeper readings at unlike ranges between a bend's faces keep them two
    obstacles as before (fig12 seed 1 at 4 ms a firing mapped a fourth meet point with it
    on). On a slow ring the same readings are strays, and the faces one wall."""
    for b in (_fine_ring(), _ring(2.8)):
        # In the sweep's sectors as ``_binned`` cuts them: the faces over seven each, seven
        # between them, each 50 % further than the one before (no two within 20 %); on a
        # slow ring each reading is its own.
        cell = np.floor(np.degrees(b) * DENSE_BINS / 360.0).astype(int)
        d = np.full(len(b), np.inf)
        d[(cell >= 118) & (cell <= 124)] = 1.40
        d[(cell >= 4) & (cell <= 10)] = 1.42
        gap = (cell >= 125) | (cell <= 3)
        along = (cell[gap] - 125) % DENSE_BINS if len(b) > 256 else (np.degrees(b[gap]) + 10) % 360
        _, rank = np.unique(along, return_inverse=True)
        d[gap] = 2.0 * 1.5**rank
        assert len(sweep_minima(b, d)) == 2
        assert len(sweep_minima(b, d, agree=True)) == (2 if len(b) > 256 else 1)


def test_one_deeper_reading_makes_the_sweep_doubtful_and_twice_the_readings_decide():
    """fig14's lab door from the junction beside it: the jambs 32 degrees apart, the view
    between them 7 degrees wide, one reading of a Nomad ring's sweep. The sweep joins them but
    says it doubts; swept twice as densely, two readings fall in the view and the jambs are
    two obstacles, where one stray reading still joins a bent wall's faces."""
    def door(step_deg: float) -> tuple[np.ndarray, np.ndarray]:
        b = _ring(step_deg)
        deg = np.degrees(b)
        d = np.full(len(b), np.inf)
        d[(deg >= 248) & (deg <= 274.5)] = 1.76  # the near jamb
        d[(deg >= 280.5) & (deg <= 306)] = 1.89  # the far jamb
        d[(deg > 274.5) & (deg < 280.5)] = 3.94  # the corridor's far wall, through the door
        return b, d

    doubts: list[float] = []
    b, d = door(5.6)
    assert np.count_nonzero(np.isfinite(d) & (d > 3.0)) == 1
    assert len(sweep_minima(b, d, doubts=doubts)) == 1
    assert len(doubts) == 1 and abs(math.degrees(doubts[0]) - 277.0) < 10.0
    doubts.clear()
    b, d = door(2.8)
    assert len(sweep_minima(b, d, doubts=doubts)) == 2 and doubts == []
    # A bent wall with one stray reading at its vertex: doubtful too, and still one wall
    # with the stray reading's neighbours swept on either side of it.
    b, d = _bent_wall_with_an_outlier(2.8)
    assert len(sweep_minima(b, d, doubts=doubts)) == 1 and len(doubts) == 1


@pytest.mark.parametrize("params", [TracerParams(), GIVING_UP])
def test_the_tracer_finds_no_meet_point_at_fig12s_cut_corner(params):
    """With ``hold_on`` (the default since stop 37) and without: homing that held on near a
    point its sweep had rejected came back to the cut corner every few seconds for minutes
    (11 meet points in 900 s, not 12)."""
    backend = create_backend({"backend": "sim", "world": "fig12", "seed": 1, "drift": "paper"})
    true_meets = [(n.x, n.y) for n in compute_gvg(backend.world).nodes if n.kind == "meet"]
    tracer = Tracer(backend.limits, params)
    robot = backend.robot
    offs: list[float] = []
    with backend:
        clock = backend.clock
        while clock.now() < 900.0 and len(offs) < 12:
            twist, events = tracer.step(
                backend.scan(), backend.odometry(), backend.status(), clock.now()
            )
            backend.command(twist)
            for ev in events:
                if isinstance(ev, MeetPointReached):
                    tp = robot.true_pose()
                    offs.append(min(math.dist((tp.x, tp.y), m) for m in true_meets))
            clock.sleep(0.1)
    assert len(true_meets) == 3
    assert len(offs) == 12 and max(offs) < 0.15, offs


def test_one_reading_off_a_plateau_does_not_cut_the_wall_out():
    """fig1's junction (1.25, 9.83): the third wall answered at 249, 254 and 266 degrees, but
    another transducer at 254 heard the far wall (2.69 m), which cut the run into pieces of
    one and two readings, too short to count; the sweep saw two obstacles and the meet point
    was rejected. With ``bridge`` (the tracer's centred_meet) the run reaches over it; a
    second reading off the plateau in a row still ends it."""
    b = np.radians([200.0, 230.0, 243.0, 249.0, 254.0, 254.5, 266.0, 276.0, 300.0])
    d = np.array([np.inf, np.inf, 2.66, 1.29, 1.23, 2.69, 1.28, np.inf, np.inf])
    assert sweep_minima(b, d) == []
    obs = sweep_minima(b, d, bridge=True)
    assert len(obs) == 1
    assert obs[0].distance_m == pytest.approx(1.28)
    assert 245.0 < math.degrees(obs[0].bearing_rad) % 360.0 < 270.0
    d2 = d.copy()
    d2[6], d2[7] = np.inf, 1.28  # no echo at 266 as well: two off the plateau in a row
    assert sweep_minima(b, d2, bridge=True) == []


def _cut_corner() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A sweep of fig12's cut corner from a meet point: two faces 61 degrees apart, 1.46 m and
    1.44 m off, and the bend's vertex between them a little farther. Bearings (radians and
    degrees) and distances."""
    b = _ring(5.6)
    deg = np.degrees(b)
    d = np.full(len(b), np.inf)
    d[(deg >= 175) & (deg <= 217)] = 1.46
    d[(deg > 217) & (deg < 230)] = 1.58  # the bend's vertex, a little farther
    d[(deg >= 230) & (deg <= 282)] = 1.44
    return b, deg, d


def test_a_bend_whose_faces_read_61_degrees_apart_is_one_wall():
    """fig12's cut corner (a 45-degree bend) read 61 degrees apart from a meet point's
    sweep, each face's plateau cut short at the bend; the faces are one wall (the readings
    between show a shallow bend's vertex, or within the wider join of the tracer's
    centred_meet), and a room's corner still two walls."""
    b, deg, d = _cut_corner()
    assert len(sweep_minima(b, d)) == 2
    assert len(sweep_minima(b, d, shallow=True)) == 1
    assert len(sweep_minima(b, d, WIDE_BEND_MERGE_RAD)) == 1
    d[(deg > 217) & (deg < 230)] = 1.75  # a vertex this deep is a bend of some 65 degrees
    assert len(sweep_minima(b, d, shallow=True)) == 2
    d[(deg > 217) & (deg < 230)] = 1.58
    d[(deg >= 175) & (deg <= 217)] = np.inf
    d[(deg >= 150) & (deg <= 190)] = 1.46  # 90 degrees from the other wall
    d[(deg > 217) & (deg < 230)] = 2.05  # a square corner's vertex, 1.41 times as far
    assert len(sweep_minima(b, d, WIDE_BEND_MERGE_RAD)) == 2
    assert len(sweep_minima(b, d, shallow=True)) == 2


def test_one_stray_reading_between_a_shallow_bends_faces_is_a_doubt_not_a_view():
    """fig12's cut corner swept from 1.4 m (trace seed 11 with a ring that kept a doorway's
    jambs apart): among the readings between the faces, 61 degrees apart, one echo read 3.25 m
    (another transducer's, or an outlier). The faces are still one wall, the sweep doubtful
    (the tracer turns the turret again); two such readings are a view past the bend."""
    b, deg, d = _cut_corner()
    stray = int(np.flatnonzero((deg > 217) & (deg < 230))[0])
    d[stray] = 3.25
    doubts: list[float] = []
    assert len(sweep_minima(b, d, shallow=True, doubts=doubts)) == 1
    assert len(doubts) == 1 and 215.0 < math.degrees(doubts[0]) < 235.0
    d[(deg > 217) & (deg < 230)] = 3.25  # a view some degrees wide: a doorway, say
    assert len(sweep_minima(b, d, shallow=True)) == 2


def test_two_strays_at_unlike_ranges_between_a_shallow_bends_faces_are_no_view():
    """fig12 seed 29 swept its cut corner from 1.4 m and read 1.64 m and 4.86 m among the
    readings of the bend's vertex: two deeper readings, so a view, and the faces two walls
    with a meet point between them that is not there (the room was mapped again). Read with
    ``agree`` they are strays; two readings that see as far are still a view."""
    b, deg, d = _cut_corner()
    between = np.flatnonzero((deg > 205) & (deg < 230))
    d[between] = 1.58  # the vertex over five readings, the faces' middles 66 degrees apart
    assert len(between) == 5 and len(sweep_minima(b, d, shallow=True)) == 1
    d[between[[1, 3]]] = [1.74, 4.86]
    assert len(sweep_minima(b, d, shallow=True)) == 2
    assert len(sweep_minima(b, d, shallow=True, agree=True)) == 1
    d[between[[1, 3]]] = [3.25, 3.3]
    assert len(sweep_minima(b, d, shallow=True, agree=True)) == 2


def test_a_wall_cut_into_pieces_by_dropouts_is_one_obstacle_when_joined():
    """fig13's meet point 5, swept 2 cm off it: one wall answered at 72, 77 and 83 degrees
    with no echo at 80, so its pieces held two readings and one, too short to count; with
    ``silent`` they are one run. A piece beside a whole run is not joined to it (that moved
    the run's middle), and a reading with an echo beyond the plateau still ends a run."""
    b = np.radians([40.0, 61.0, 72.0, 77.0, 80.0, 83.0, 94.0, 120.0])
    d = np.array([np.inf, np.inf, 1.28, 1.28, np.inf, 1.25, 2.67, np.inf])
    assert sweep_minima(b, d) == []
    (wall,) = sweep_minima(b, d, silent=True)
    assert wall.distance_m == pytest.approx(1.28) and math.degrees(wall.bearing_rad) == (
        pytest.approx(77.5)
    )
    d[4] = 2.6  # an echo from beyond: a view past two obstacles, not a dropout
    assert sweep_minima(b, d, silent=True) == []
    b = np.radians([60.0, 100.0, 105.0, 110.0, 115.0, 120.0, 160.0])
    d = np.array([np.inf, 1.40, 1.40, 1.41, np.inf, 1.40, np.inf])
    (wall,) = sweep_minima(b, d, silent=True)
    assert math.degrees(wall.bearing_rad) == pytest.approx(105.0)


def _indent_from_the_corridor(step_deg: float) -> tuple[np.ndarray, np.ndarray]:
    """fig16's corridor meet point as its sweep saw it (seed 2, 41 s): the far wall, and across
    the corridor the indent: its near corner, its back wall deeper, its far corner, with
    deeper readings between where the view reaches each inner corner."""
    b = _ring(step_deg)
    deg = np.degrees(b)
    d = np.full(len(b), np.inf)
    d[(deg >= 30) & (deg <= 75)] = 1.16  # the far wall
    d[(deg >= 180) & (deg <= 196)] = 1.12  # the near corner
    d[(deg > 196) & (deg < 212)] = 1.44  # past it, into the inner corner
    d[(deg >= 212) & (deg <= 252)] = 1.25  # the indent's back wall
    d[(deg > 252) & (deg < 261)] = 1.48
    d[(deg >= 261) & (deg <= 278)] = 1.16  # the far corner
    return b, d


@pytest.mark.parametrize("step_deg", [2.8, 5.6])
def test_a_corner_is_not_one_bent_wall_with_the_wall_behind_it(step_deg):
    b, d = _indent_from_the_corridor(step_deg)
    # Joined as one bent wall (the readings between are less than 25 % deeper), the corners
    # and the back wall hid the meet point: two obstacles, no third equidistant.
    assert len(sweep_minima(b, d)) < 3
    # The readings between reach beyond the vertex a corner and a wall would make: three
    # walls equidistant to 4 cm, the back wall 9 cm further.
    obs = sweep_minima(b, d, vertex=True)
    found = _bearings(obs[:3])
    assert all(abs(f - t) <= 4 for f, t in zip(found, [52, 188, 270], strict=True)), found
    assert obs[2].distance_m - obs[0].distance_m < 0.05


def test_the_readings_of_a_true_bent_wall_stay_within_its_vertex():
    b = _ring()
    deg = np.degrees(b)
    d = np.full(len(b), np.inf)
    d[(deg >= 330) & (deg <= 350)] = 1.40
    d[(deg > 350) | (deg < 10)] = 1.52  # the vertex of faces 1.40 and 1.42 m off: 1.50 m
    d[(deg >= 10) & (deg <= 30)] = 1.42
    assert len(sweep_minima(b, d, vertex=True)) == 1


def _near_bearings(obs, within_m: float = 1.3) -> list[float]:
    return _bearings([o for o in obs if o.distance_m <= within_m])


@pytest.mark.parametrize("step_deg", [2.8, 5.6])
def test_a_recess_back_wall_is_not_one_bent_wall_with_its_corners(step_deg):
    b, d = _indent_from_the_corridor(step_deg)
    # Chained corner to back wall to corner, the indent read as one obstacle.
    assert len(_near_bearings(sweep_minima(b, d))) == 2
    obs = sweep_minima(b, d, recess=True)
    assert len(_near_bearings(obs)) == 4
    (back,) = [o for o in obs if 1.2 < o.distance_m < 1.3]
    assert math.degrees(back.bearing_rad) % 360 == pytest.approx(232.0, abs=3.0)


@pytest.mark.parametrize("step_deg", [2.8, 5.6])
def test_a_recess_back_wall_whose_side_lobes_reach_a_corner_is_still_an_obstacle(step_deg):
    b, d = _indent_from_the_corridor(step_deg)
    deg = np.degrees(b)
    # Side lobes carry the back wall's echo right up to the near corner's plateau: its run
    # borders a lower one, a slope by Fig. 4's rule.
    d[(deg > 196) & (deg < 212)] = 1.25
    assert len(_near_bearings(sweep_minima(b, d))) == 3
    assert len(_near_bearings(sweep_minima(b, d, recess=True))) == 4


def test_a_plateau_beside_a_nearer_wall_on_one_side_only_is_a_slope_still():
    # A wall's end: the wall 1.0 m off, its end's corner echo 1.3 m off just past it, and
    # nothing nearer beyond. Not framed by two nearer obstacles: no recess.
    b = _ring()
    deg = np.degrees(b)
    d = np.full(len(b), np.inf)
    d[(deg >= 60) & (deg <= 120)] = 1.0
    d[(deg > 120) & (deg <= 145)] = 1.3
    (wall,) = sweep_minima(b, d, recess=True)
    assert wall.distance_m == 1.0
    assert _bearings(sweep_minima(b, d)) == _bearings([wall])


def test_the_middle_face_of_a_concave_bend_is_no_recess():
    # fig12's cut corner (seed 1, 341 s): two faces 1.41 m and 1.44 m off, the cut between
    # them 1.46-1.55 m, a little deeper, and no view past them between: a bent wall, not a
    # recess's back wall with a meet point before it.
    b = _ring(5.6)
    deg = np.degrees(b)
    d = np.full(len(b), np.inf)
    d[(deg >= 95) & (deg <= 135)] = 1.41
    d[(deg > 135) & (deg < 165)] = 1.55
    d[(deg >= 165) & (deg <= 200)] = 1.44
    assert _bearings(sweep_minima(b, d, recess=True)) == _bearings(sweep_minima(b, d))
    assert len(sweep_minima(b, d)) == 2
    # A view past the cut on one side, into an inner corner behind it: a recess.
    d[(deg > 135) & (deg <= 142)] = 1.70
    assert len(sweep_minima(b, d, recess=True)) == 3


def test_a_reading_by_a_bend_vertex_is_no_view_past_it():
    # fig12's cut corner (seed 3, 394 s): faces 1.38 m and 1.37 m off, the bend's vertex a
    # plateau of its own 1.47 m off, and beside it one reading 1.56 m off: deeper than the
    # plateau, but short of the 1.58 m a bend of the plateau and a face make. Taken for an
    # inner corner's view, the plateau was a recess's back wall, the faces two walls, and
    # the cut corner a meet point.
    b = _ring(5.6)
    deg = np.degrees(b)
    d = np.full(len(b), np.inf)
    d[(deg >= 150) & (deg <= 178)] = 1.38
    d[(deg > 178) & (deg < 183)] = 1.56
    d[(deg >= 183) & (deg <= 198)] = [1.47, 1.48, 1.47]
    d[(deg > 198) & (deg <= 203)] = 1.40
    d[(deg > 208) & (deg <= 240)] = 1.37  # a dropout between: the plateau is no slope
    assert len(sweep_minima(b, d, recess=True)) == 1
    # Beyond that vertex the view passes the bend: a recess's inner corner.
    d[(deg > 178) & (deg < 183)] = 1.66
    assert len(sweep_minima(b, d, recess=True)) == 3


def test_a_sweep_counts_the_firings_that_read_the_minimum_range():
    def scan(ranges: list[float], stamp: float) -> SonarScan:
        yaw = np.arange(4) * math.pi / 2
        return SonarScan(
            ranges_m=np.asarray(ranges),
            x_m=0.23 * np.cos(yaw),
            y_m=0.23 * np.sin(yaw),
            yaw_rad=yaw,
            stamps_s=np.full(4, stamp),
            min_range_m=0.15,
            max_range_m=6.5,
            half_beam_rad=math.radians(12.5),
        )

    sweep = Sweep()
    sweep.add(scan([1.0, 0.15, np.nan, 0.3], 0.0))
    sweep.add(scan([1.0, 0.15, np.nan, 0.3], 0.0))  # the same firings again: not new
    assert sweep.touching == 1
    sweep.add(scan([0.155, 0.17, 2.0, 0.3], 1.0))
    assert sweep.touching == 2  # 0.155 is within a centimetre of it, 0.17 is not


def test_no_meet_point_beside_something_too_near_to_measure():
    """fig13 seed 9 at drift paper: the robot homed 0.27 m from a cabinet's convex corner, which
    no transducer heard but at the minimum range, and reported a meet point of three walls
    1.7 m off, 0.99 m from any true one."""
    backend = create_backend({"backend": "sim", "world": "fig13", "seed": 9, "drift": "paper"})
    report = run_trace(backend, 12).report
    assert report["meet_point_error_max_m"] <= 0.10
    assert report["collisions"] == 0


def _captured(text: str) -> tuple[np.ndarray, np.ndarray]:
    """A sweep as the simulated robot recorded it: ``bearing:distance`` pairs, degrees and
    metres, ``inf`` for no echo."""
    pairs = [p.split(":") for p in text.split()]
    return np.radians([float(b) for b, _ in pairs]), np.array([float(d) for _, d in pairs])


# fig13 seed 8 at 50 s, homed onto the junction at (5.57, 1.55): the wall the robot stands
# 1.58 m off (321-11 degrees), the corner where the cabinet meets it (2.04-2.12 m), and the
# cabinet's own corner (1.69-1.74 m), 58 degrees from the wall's middle.
_FIG13_JUNCTION = """
0:inf 6:1.59 11:1.56 17:inf 22:2.12 28:2.04 33:1.74 38:1.69 44:1.71 50:1.71 55:3.65 60:3.52
66:inf 71:4.85 77:4.87 82:2.84 88:2.88 93:2.86 98:2.87 104:1.52 109:1.54 115:1.52 120:1.54
126:inf 131:inf 137:3.63 142:3.60 148:3.71 153:3.69 159:5.30 164:3.07 166:3.04 171:2.99
177:1.55 182:1.57 187:1.62 193:1.59 198:inf 204:inf 211:inf 217:3.03 222:2.99 228:2.99
234:3.02 240:inf 245:5.63 251:5.53 258:5.56 263:5.47 269:5.69 274:5.88 281:5.87 286:inf
292:inf 297:inf 304:inf 310:inf 315:inf 321:1.58 327:inf 333:1.59 338:1.58 344:1.58
349:1.55 355:1.58
"""

# fig12 seed 29 at 417 s, swept twice at the room's cut corner: two runs 1.38 m off whose
# middles lie 22 degrees apart, and between them four readings of the bend's vertex,
# 1.49-1.52 m.
_FIG12_CUT_CORNER = """
1:3.87 5:3.86 6:3.84 11:3.87 12:3.92 17:3.79 17:3.96 23:3.89 24:3.82 28:6.32 29:6.25 34:6.32
35:6.29 39:6.23 40:6.34 46:6.34 46:6.43 51:6.51 51:6.29 57:inf 57:inf 59:inf 62:inf 68:inf
68:inf 73:inf 74:inf 79:inf 79:inf 79:inf 84:inf 89:inf 90:inf 95:inf 95:inf 99:1.40
101:inf 101:inf 106:1.42 111:1.41 112:1.36 117:1.38 117:1.39 122:1.64 123:inf 128:1.35
133:1.38 133:1.41 139:1.50 139:inf 144:1.51 145:1.49 150:1.52 150:1.38 155:1.38 155:1.32
160:4.86 161:1.37 166:1.39 166:1.41 172:inf 172:1.38 177:1.35 177:1.40 182:1.43 183:1.37
188:1.40 188:inf 193:1.39 194:inf 198:1.74 199:1.74 204:1.82 204:1.77 210:1.78 210:1.74
215:1.77 215:1.73 221:1.75 222:1.74 226:1.81 228:inf 232:inf 233:inf 237:1.82 239:1.77
243:inf 244:inf 249:inf 250:inf 255:inf 255:inf 260:inf 261:inf 266:inf 268:inf 272:inf
273:inf 277:inf 277:inf 279:inf 283:inf 284:inf 290:6.63 291:6.65 295:6.69 296:6.55
301:6.52 302:6.69 302:6.51 307:6.64 308:6.60 313:6.57 314:6.58 319:1.47 320:1.47 324:1.47
325:1.43 328:1.41 330:1.48 331:1.45 336:1.45 337:1.46 342:inf 343:inf 347:inf 348:inf
353:inf 354:inf 359:inf
"""


def _sweep_as_the_tracer_reads_it(text: str, vertex: bool) -> list:
    b, d = _captured(text)
    return sweep_minima(
        b, d, silent=True, shallow=True, vertex=vertex, recess=True, agree=True
    )


def test_a_cabinets_corner_beyond_the_vertex_it_would_make_with_the_wall_is_an_obstacle():
    """Joined with the wall as one bent wall (the corner's 1.71 m is within 1.25 times the
    wall's 1.58 m), the cabinet's corner hid the junction 0.29 m on: its dead end was never
    mapped. The readings between reach 2.04-2.12 m, beyond the 1.89 m vertex a wall and a
    face there would make."""
    joined = _sweep_as_the_tracer_reads_it(_FIG13_JUNCTION, vertex=False)
    assert 42 not in _bearings(joined)
    apart = _sweep_as_the_tracer_reads_it(_FIG13_JUNCTION, vertex=True)
    near = [o for o in apart if o.distance_m < 2.0]
    assert _bearings(near) == [42, 112, 185, 344]
    assert [round(o.distance_m, 2) for o in near] == [1.53, 1.58, 1.58, 1.71]
    assert TracerParams().sweep_vertex  # as the tracer sweeps by default since stop 53


def test_readings_within_a_shallow_bends_vertex_keep_a_cut_corner_one_wall(monkeypatch):
    """Run middles 22 degrees apart put the vertex of faces 1.38 m off at 1.41 m, and the
    cut corner's own vertex (1.49-1.52 m) beyond it: two walls and a meet point mid-room.
    No bend of up to 55 degrees has its vertex deeper than 1.12 times its faces (1.55 m)."""
    obs = _sweep_as_the_tracer_reads_it(_FIG12_CUT_CORNER, vertex=True)
    assert len([o for o in obs if o.distance_m < 1.5]) == 2
    # Without that floor under the vertex, the faces were two walls.
    monkeypatch.setattr(sweep_module, "SHALLOW_BEND_RATIO", 1.0)
    obs = _sweep_as_the_tracer_reads_it(_FIG12_CUT_CORNER, vertex=True)
    assert len([o for o in obs if o.distance_m < 1.5]) == 3

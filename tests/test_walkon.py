"""Going through the expected junction without homing: the traversal's own path says where
the robot went (fig16's weak meet points)."""

from __future__ import annotations

import itertools
import math

import pytest

from hal.types import Odometry
from tslam.core.edgepaths import EdgePath, EdgePaths
from tslam.core.localize import Tolerances
from tslam.core.topomap import TopoMap
from tslam.core.walkon import walk_back, walk_on


def rad(deg: float) -> float:
    return math.radians(deg) % (2 * math.pi)


def indent_map() -> tuple[TopoMap, int, int, int]:
    """fig16's indent: boundary ``b`` -- 0.5 m -- junction ``w`` -- 0.4 m -- junction ``m``.

    ``w`` (at the origin) has departures 0 deg (to ``m``), 150 deg (to ``b``) and 210 deg
    (unexplored); ``m`` has 180 deg (to ``w``), 90 deg and 270 deg (both unexplored)."""
    t = TopoMap()
    w = t.add_meet(0.9, [rad(0), rad(150), rad(210)], (0.0, 0.0))
    m = t.add_meet(1.1, [rad(90), rad(180), rad(270)], (0.4, 0.0))
    b = t.add_boundary(0.4, (-0.43, 0.25))
    t.connect(b, 0, w, 1, 0.5)
    t.connect(w, 0, m, 1, 0.4)
    return t, b, w, m


def path_of(points: list[tuple[float, float]], start: int = 0) -> EdgePath:
    """The record of a robot driving through ``points``, odometry every centimetre."""
    paths = EdgePaths(spacing_m=0.05)
    d = 0.0
    paths.add(Odometry(points[0][0], points[0][1], 0.0, 0.0, d, d))
    for (x0, y0), (x1, y1) in itertools.pairwise(points):
        n = max(1, round(math.hypot(x1 - x0, y1 - y0) / 0.01))
        for i in range(1, n + 1):
            d += math.hypot(x1 - x0, y1 - y0) / n
            paths.add(Odometry(x0 + (x1 - x0) * i / n, y0 + (y1 - y0) * i / n, 0.0, 0.0, d, d))
    path = paths.live(start, d)
    assert path is not None
    return path


def path_through(*legs: tuple[float, float]) -> EdgePath:
    """A path from the boundary: legs of (heading in degrees, metres)."""
    x, y = 0.5 * math.cos(rad(150)), 0.5 * math.sin(rad(150))
    points = [(x, y)]
    for heading, metres in legs:
        x += metres * math.cos(rad(heading))
        y += metres * math.sin(rad(heading))
        points.append((x, y))
    return path_of(points)


def test_through_the_junction_onto_its_unexplored_departure():
    t, b, w, _ = indent_map()
    path = path_through((-30, 0.5), (210, 0.7))  # in to w, then out along 210 deg
    walk = walk_on(t, b, 0, path, 1.2, Tolerances())
    assert walk is not None and not walk.known
    assert (walk.node, walk.port, walk.passed) == (w, 2, (w,))
    assert walk.rest_m == pytest.approx(0.7, abs=1e-9)


def test_through_two_junctions_onto_the_second_ones_departure():
    t, b, w, m = indent_map()
    path = path_through((-30, 0.5), (0, 0.4), (270, 2.0))  # through w and m, then south
    walk = walk_on(t, b, 0, path, 2.9, Tolerances())
    assert walk is not None and not walk.known
    assert (walk.node, walk.port, walk.passed) == (m, 2, (w, m))
    assert walk.rest_m == pytest.approx(2.0, abs=1e-9)
    north = walk_on(t, b, 0, path_through((-30, 0.5), (0, 0.4), (90, 2.0)), 2.9, Tolerances())
    assert north is not None and (north.node, north.port) == (m, 0)


def test_a_walk_that_ends_on_a_mapped_node_names_it_and_its_port():
    t, b, w, m = indent_map()
    walk = walk_on(t, b, 0, path_through((-30, 0.5), (0, 0.4)), 0.95, Tolerances())
    assert walk is not None and walk.known and (walk.node, walk.port) == (m, 1)
    assert walk.passed == (w,)


def test_no_walk_when_the_turn_fits_no_departure_or_two_alike_or_the_lengths_do_not_add_up():
    t, b, _, _ = indent_map()
    tol = Tolerances()
    # Out of w at 285 deg: 75 deg from the way to m and from the unexplored departure.
    assert walk_on(t, b, 0, path_through((-30, 0.5), (285, 0.7)), 1.2, tol) is None
    # Arrived about where w is: as likely w itself, read otherwise.
    assert walk_on(t, b, 0, path_through((-30, 0.5), (210, 0.1)), 0.6, tol) is None
    # A record that does not cover the traversal (the edge's length says 2 m).
    assert walk_on(t, b, 0, path_through((-30, 0.5), (0, 0.4), (90, 0.1)), 2.0, tol) is None
    assert walk_on(t, b, 0, path_through((-30, 0.5), (0, 0.4), (90, 1.1)), 2.0, tol) is not None
    # A departure of the map that has no edge yet gives nothing to walk from.
    t2 = TopoMap()
    w2 = t2.add_meet(0.9, [rad(0), rad(150), rad(210)], (0.0, 0.0))
    assert walk_on(t2, w2, 0, path_through((0, 1.0)), 1.0, tol) is None


def test_a_departure_not_held_comes_back_through_its_node_and_walks_on_from_there():
    t, b, w, m = indent_map()
    # Out of w along its unexplored 210 deg departure for 0.2 m, back through w, on to m.
    out = (0.2 * math.cos(rad(210)), 0.2 * math.sin(rad(210)))
    path = path_of([(0.0, 0.0), out, (0.01, 0.0), (0.4, 0.0), (0.4, -1.0)], start=w)
    walk = walk_back(t, w, 2, path, path.length_m, Tolerances())
    assert walk is not None and not walk.known and (walk.node, walk.port) == (m, 2)
    assert walk.passed == (w, m) and walk.rest_m == pytest.approx(1.0, abs=0.1)
    # A path that goes out and never comes back says nothing.
    straight = path_through((-30, 0.5), (-30, 1.0))
    assert walk_back(t, b, 0, straight, straight.length_m, Tolerances()) is None

"""The record of recently traced edges that places a missed junction on its first pass."""

from __future__ import annotations

import itertools

import pytest

from hal.types import Odometry
from tslam.core.edgepaths import EdgePaths


def odo(x: float, y: float, d: float) -> Odometry:
    return Odometry(x, y, 0.0, 0.0, d, d)


def test_a_finished_edge_is_kept_as_arc_length_and_points():
    paths = EdgePaths(spacing_m=0.1)
    for i in range(41):  # 2 m east, odometry every 0.05 m
        paths.add(odo(0.05 * i, 0.0, 10.0 + 0.05 * i))
    paths.finish(7, start=3, distance_m=12.0)
    p = paths.get(7)
    assert p is not None and p.start == 3 and p.end_distance_m == 12.0
    assert p.length_m == pytest.approx(2.0, abs=0.06)
    gaps = [b[0] - a[0] for a, b in itertools.pairwise(p.points)]
    assert min(gaps) >= 0.1 - 1e-9 and max(gaps) <= 0.15 + 1e-9
    s, off = p.nearest(1.0, 0.3)
    assert s == pytest.approx(1.0, abs=0.06) and off == pytest.approx(0.3, abs=0.06)
    assert p.at(0.55) == pytest.approx((0.55, 0.0), abs=1e-9)
    assert p.at(-1.0) == pytest.approx(p.at(0.0)) and p.at(99.0) == pytest.approx(p.at(p.length_m))


def test_only_the_latest_edges_are_kept_and_a_restart_forgets_the_live_one():
    paths = EdgePaths(keep=2, spacing_m=0.01)
    for e in (1, 2, 3):
        paths.add(odo(0.0, 0.0, e))
        paths.add(odo(1.0, 0.0, e + 0.5))
        paths.finish(e, start=e, distance_m=e + 0.5)
    assert paths.get(1) is None and paths.get(2) is not None and paths.get(3) is not None
    paths.add(odo(0.0, 0.0, 9.0))
    paths.add(odo(1.0, 0.0, 9.5))
    paths.restart()
    paths.add(odo(5.0, 0.0, 9.6))
    paths.finish(4, start=1, distance_m=9.6)  # one point is no path
    assert paths.get(4) is None


def test_a_pass_is_put_in_the_measure_of_the_edge_length():
    """The encoders count the weave the edge's own length leaves out: the pass's distances
    are scaled to the measured length, unless the two are too far apart to be one pass."""
    paths = EdgePaths(spacing_m=0.1)
    for i in range(41):
        paths.add(odo(0.05 * i, 0.0, 0.05 * i))
    p = paths.live(start=0, distance_m=2.0)
    assert p is not None
    q = p.measured_as(0.9 * p.length_m)
    assert q.length_m == pytest.approx(0.9 * p.length_m)
    assert q.at(0.9) == pytest.approx(p.at(1.0))  # the same place, a shorter measure
    assert p.measured_as(0.5 * p.length_m) is p  # not this traversal: left for the check
    assert p.measured_as(1.5 * p.length_m) is p

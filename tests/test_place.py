"""A junction of two close meet points is read as one place, with the edges of both, from
whichever of the two the robot homed onto; an obstacle that makes no meet point nearby (too
far, or behind a nearer one) adds nothing."""

from __future__ import annotations

import math

import pytest

from tslam.core import laws
from tslam.core.place import place_obstacles
from tslam.core.sensing import Obstacle
from tslam.core.tracer import TracerParams
from tslam.programs.trace_cmd import tracer_params


def _corner(x: float, y: float) -> Obstacle:
    """A convex corner at (x, y), seen from the origin."""
    d = math.hypot(x, y)
    return Obstacle(d, x, y, -x / d, -y / d, math.atan2(y, x))


def _near(obs: list[Obstacle], tol: float = 0.10) -> list[Obstacle]:
    obs = sorted(obs, key=lambda o: o.distance_m)
    return [o for o in obs if o.distance_m - obs[0].distance_m <= tol]


def _degrees(obs: list[Obstacle]) -> list[int]:
    return [round(math.degrees(b)) for b in laws.departure_bearings(obs)]


def test_a_second_meet_point_a_quarter_metre_off_adds_its_obstacle_and_edge():
    # The robot stands on the meet point of west, north and south, 2 m away; a corner 2.25 m
    # to the east makes a second meet point (north, south, east) 0.25 m east: fig1's pair.
    west, north, south, east = _corner(-2, 0), _corner(0, 2), _corner(0, -2), _corner(2.25, 0)
    obs = sorted([west, north, south, east], key=lambda o: o.distance_m)
    near = _near(obs)
    assert len(near) == 3
    place = place_obstacles(obs, near, radius_m=0.4, tol_m=0.05)
    assert sorted(o.bearing_rad for o in place) == sorted(o.bearing_rad for o in obs)
    # Four edges out, one between each two neighbours: north-east and south-east leave
    # from the second point, and the single point's east edge is not one of them.
    assert _degrees(place) == [45, 135, 225, 315]
    assert _degrees(near) == [0, 135, 225]


def test_from_the_other_point_the_place_has_the_same_four_edges():
    # The same junction, the robot on the east meet point (0.25 m east of the first).
    shift = 0.25
    obs = [_corner(-2 - shift, 0), _corner(-shift, 2), _corner(-shift, -2), _corner(2.0, 0)]
    obs.sort(key=lambda o: o.distance_m)
    place = place_obstacles(obs, _near(obs), radius_m=0.4, tol_m=0.05)
    assert len(place) == 4
    assert len(_degrees(place)) == 4


def test_a_meet_point_beyond_the_radius_is_another_place():
    west, north, south = _corner(-2, 0), _corner(0, 2), _corner(0, -2)
    east = _corner(3.0, 0)  # the second meet point 1 m east
    obs = [west, north, south, east]
    place = place_obstacles(obs, _near(obs), radius_m=0.4, tol_m=0.05)
    assert len(place) == 3 and all(o is not east for o in place)


def test_an_obstacle_behind_a_nearer_one_makes_no_meet_point():
    # A corner 2.3 m west, behind the west corner at 2 m: the point equidistant to it and
    # north and south lies 0.3 m west, where the west corner is nearer still.
    west, north, south, behind = _corner(-2, 0), _corner(0, 2), _corner(0, -2), _corner(-2.3, 0)
    obs = [west, north, south, behind]
    place = place_obstacles(obs, _near(obs), radius_m=0.4, tol_m=0.05)
    assert len(place) == 3 and all(o is not behind for o in place)


@pytest.mark.parametrize("corners", [True, False])
def test_a_meet_point_between_two_corners_and_a_wall_is_sought_as_three_corners(corners):
    # fig16's corridor meet point: the far wall 1.14 m east, the indent's corners 1.14 m off
    # to the north-west and south-west, its back wall 1.26 m west. The weak meet point lies
    # 0.36 m west, equidistant to the corners and the back wall; as three walls, 0.53 m west.
    east, back = _corner(1.14, 0.0), _corner(-1.26, 0.0)
    north, south = _corner(-0.859, 0.75), _corner(-0.859, -0.75)
    obs = sorted([east, back, north, south], key=lambda o: o.distance_m)
    place = place_obstacles(obs, _near(obs), radius_m=0.4, tol_m=0.05, corners=corners)
    assert (len(place), any(o is back for o in place)) == ((4, True) if corners else (3, False))


def test_radius_zero_reads_the_point_alone():
    obs = [_corner(-2, 0), _corner(0, 2), _corner(0, -2), _corner(2.25, 0)]
    near = _near(sorted(obs, key=lambda o: o.distance_m))
    assert place_obstacles(obs, near, radius_m=0.0, tol_m=0.05) == near


def test_the_place_reading_is_on_by_default_and_its_old_switch_still_runs():
    assert TracerParams().place_radius_m == 0.4
    assert tracer_params([]).place_radius_m == 0.4
    assert tracer_params(["place"]).place_radius_m == 0.4

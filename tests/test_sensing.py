"""Sonar ring to obstacles: the Fig. 4 rules, spike rejection, motion compensation."""

from __future__ import annotations

import math

import numpy as np
import pytest

from hal.types import Odometry, SonarScan
from tslam.core.sensing import PoseHistory, RingSensor, SensingParams, local_minima


def ring_points(ranges, n=None):
    r = np.asarray(ranges, dtype=float)
    n = n or len(r)
    ang = np.arange(n) * 2 * math.pi / n
    return np.column_stack([r * np.cos(ang), r * np.sin(ang)])


def test_fig4_only_local_minima_are_obstacles():
    # Eight sensors as in Fig. 4: H (index 7) is the smallest; A (0) is second smallest but
    # next to H, so not a minimum; C (2) is the second obstacle.
    obs = local_minima(ring_points([12, 30, 14, 25, 40, 40, 22, 10]), merge_rad=0.0)
    assert [round(o.distance_m) for o in obs] == [10, 14]  # H, then C
    assert obs[0].bearing_rad == pytest.approx(math.radians(-45))
    assert obs[1].bearing_rad == pytest.approx(math.radians(90))
    # The gradient points away from the obstacle.
    assert (obs[0].gx, obs[0].gy) == pytest.approx((-0.7071, 0.7071), abs=1e-3)


def test_two_equal_adjacent_readings_are_one_obstacle_between_them():
    obs = local_minima(ring_points([5, 2, 2, 5, 6, 7, 6, 5]), merge_rad=0.0)
    first = obs[0]
    assert first.distance_m == pytest.approx(2.0)
    assert first.bearing_rad == pytest.approx(math.radians(67.5))  # between 45 and 90


def test_no_echo_separates_and_is_never_an_obstacle():
    r = [np.nan] * 16
    r[4], r[12] = 1.0, 1.2
    obs = local_minima(ring_points(r))
    assert [o.distance_m for o in obs] == pytest.approx([1.0, 1.2])
    assert local_minima(ring_points([np.nan] * 16)) == []


def test_one_wall_split_by_a_silent_transducer_is_one_obstacle():
    r = [5.0] * 16
    r[3], r[4], r[5] = 1.05, np.nan, 1.0
    assert len([o for o in local_minima(ring_points(r)) if o.distance_m < 2]) == 1


def _scan(ranges, stamps, yaw0=0.0):
    n = len(ranges)
    yaw = yaw0 + np.arange(n) * 2 * math.pi / n
    return SonarScan(
        ranges_m=np.asarray(ranges, dtype=float),
        x_m=0.23 * np.cos(yaw),
        y_m=0.23 * np.sin(yaw),
        yaw_rad=yaw,
        stamps_s=np.asarray(stamps, dtype=float),
        min_range_m=0.15,
        max_range_m=6.5,
        half_beam_rad=math.radians(12.5),
    )


def test_old_wall_reading_is_carried_into_the_current_frame():
    sensor = RingSensor()
    # At t = 0 transducer 0 hears a wall 2 m ahead (2.23 m from the centre); then the robot
    # drives 0.5 m toward it without that transducer firing again.
    ranges = [np.nan] * 16
    ranges[0] = 2.0
    sensor.update(_scan(ranges, [0.0] * 16), Odometry(0.0, 0.0, 0.0, 0.0, 0.0))
    obs = sensor.update(_scan(ranges, [0.0] * 16), Odometry(0.5, 0.0, 0.0, 0.0, 1.0))
    assert obs[0].distance_m == pytest.approx(1.73, abs=1e-9)
    # Turning in place rotates it in the robot frame, at the same distance.
    obs = sensor.update(_scan(ranges, [0.0] * 16), Odometry(0.5, 0.0, 0.5, 0.0, 2.0))
    assert obs[0].distance_m == pytest.approx(1.73, abs=1e-9)
    assert obs[0].bearing_rad == pytest.approx(-0.5, abs=1e-9)


def test_a_lone_spike_is_held_until_confirmed():
    sensor = RingSensor()
    base = [3.0] * 16
    odo = Odometry(0.0, 0.0, 0.0, 0.0, 0.0)
    sensor.update(_scan(base, np.zeros(16)), odo)
    spiky = list(base)
    spiky[5] = 0.5
    stamps = np.zeros(16)
    stamps[5] = 1.0
    obs = sensor.update(_scan(spiky, stamps), Odometry(0.0, 0.0, 0.0, 0.0, 1.0))
    assert min(o.distance_m for o in obs) > 3.0  # held back
    stamps[5] = 2.0
    obs = sensor.update(_scan(spiky, stamps), Odometry(0.0, 0.0, 0.0, 0.0, 2.0))
    assert obs[0].distance_m == pytest.approx(0.73)  # repeated: it is real


def test_a_second_spike_far_below_a_held_one_is_not_its_confirmation():
    """On a ring that fires fast, two outliers a few firings apart on one transducer happen:
    the second is another spike, not the first one repeated."""
    sensor = RingSensor()
    base = [3.0] * 16
    sensor.update(_scan(base, np.zeros(16)), Odometry(0.0, 0.0, 0.0, 0.0, 0.0))
    first = list(base)
    first[5] = 1.6
    stamps = np.zeros(16)
    stamps[5] = 0.1
    obs = sensor.update(_scan(first, stamps), Odometry(0.0, 0.0, 0.0, 0.0, 0.1))
    assert min(o.distance_m for o in obs) > 3.0  # held back
    second = list(base)
    second[5] = 0.2
    stamps[5] = 0.2
    obs = sensor.update(_scan(second, stamps), Odometry(0.0, 0.0, 0.0, 0.0, 0.2))
    assert min(o.distance_m for o in obs) > 3.0  # held back too
    stamps[5] = 0.3
    obs = sensor.update(_scan(second, stamps), Odometry(0.0, 0.0, 0.0, 0.0, 0.3))
    assert obs[0].distance_m == pytest.approx(0.43)  # repeated: it is real


def _cut_corner(between: float, far_face: float = 1.38) -> np.ndarray:
    """A 16-transducer ring near a 45-degree cut corner: one face answers two transducers
    (a plateau at 11.25 degrees), the other one transducer at 67.5 degrees, 56 degrees
    apart; ``between`` is the reading at 45 degrees, toward the bend's vertex. A block
    across the corridor answers at 180 degrees."""
    r = np.full(16, 3.0)
    r[15], r[0], r[1], r[2], r[3], r[4] = 1.6, 1.40, 1.40, between, far_face, 1.6
    r[7], r[8], r[9] = 1.45, 1.3, 1.45
    return ring_points(r)


def test_two_faces_of_a_flat_bend_are_one_obstacle_up_to_the_bend_angle():
    bend = {"bend_merge_rad": math.radians(60.0)}
    obs = local_minima(_cut_corner(1.55), **bend)
    # The vertex reads a little deeper than the faces: one bent wall, the nearer face for it.
    assert [round(o.distance_m, 2) for o in obs[:2]] == [1.3, 1.38]
    assert len([o for o in obs if o.distance_m < 2]) == 2
    # Without the bend rule the ring sees three walls nearly equidistant: a meet point that
    # the sweep (which joins them) would reject every time.
    assert len([o for o in local_minima(_cut_corner(1.55)) if o.distance_m < 2]) == 3


@pytest.mark.parametrize(
    "between, far_face",
    [(2.5, 1.38), (np.nan, 1.38), (1.55, 1.9)],
    ids=["a view past the faces", "no echo between", "one face much farther"],
)
def test_two_minima_are_two_obstacles_unless_they_could_be_one_bend(between, far_face):
    obs = local_minima(_cut_corner(between, far_face), bend_merge_rad=math.radians(60.0))
    assert len([o for o in obs if o.distance_m < 2]) == 3


def _corner_in_the_gap(gap_hold_s: float) -> tuple[RingSensor, list[float], np.ndarray]:
    """Transducer 0 hears a cabinet's corner 0.83 m ahead (twice: a lone short reading is
    held as a spike); then the robot turns 11.25 degrees, which puts the corner 15.5 degrees
    off the axes of transducers 0 and 15 both (the beam is +/-12.5), and transducer 0 hears
    the wall beyond, 3 m off."""
    sensor = RingSensor(SensingParams(gap_hold_s=gap_hold_s))
    far = [3.0] * 16
    far[8] = 2.5  # a wall behind
    stamps = np.zeros(16)
    sensor.update(_scan(far, stamps), Odometry(0.0, 0.0, 0.0, 0.0, 0.0))
    near = list(far)
    near[0] = 0.6
    for t in (0.1, 0.2):
        stamps[0] = t
        sensor.update(_scan(near, stamps), Odometry(0.0, 0.0, 0.0, 0.0, t))
    stamps[0] = 0.4
    return sensor, far, stamps


def test_a_corner_that_slips_between_two_beams_is_kept_where_it_was():
    turned = Odometry(0.0, 0.0, math.radians(11.25), 0.0, 0.4)
    sensor, far, stamps = _corner_in_the_gap(0.0)
    assert min(o.distance_m for o in sensor.update(_scan(far, stamps), turned)) > 2.0
    sensor, far, stamps = _corner_in_the_gap(3.0)
    obs = sensor.update(_scan(far, stamps), turned)
    assert obs[0].distance_m == pytest.approx(0.83, abs=1e-6)  # the point, not a wall
    assert obs[0].bearing_rad == pytest.approx(math.radians(-11.25), abs=1e-6)
    # Turned back, transducer 0's beam covers the point again and hears past it: gone.
    stamps[0] = 0.6
    obs = sensor.update(_scan(far, stamps), Odometry(0.0, 0.0, 0.0, 0.0, 0.6))
    assert min(o.distance_m for o in obs) > 2.0


def test_a_corner_kept_in_a_gap_is_let_go_after_gap_hold_s():
    sensor, far, stamps = _corner_in_the_gap(1.0)
    heading = math.radians(11.25)
    for t in (0.4, 1.0):
        stamps[0] = t
        obs = sensor.update(_scan(far, stamps), Odometry(0.0, 0.0, heading, 0.0, t))
        assert obs[0].distance_m == pytest.approx(0.83, abs=1e-6)
    stamps[0] = 1.3  # the corner was heard at 0.2 s
    obs = sensor.update(_scan(far, stamps), Odometry(0.0, 0.0, heading, 0.0, 1.3))
    assert min(o.distance_m for o in obs) > 2.0


def test_pose_history_interpolates_a_heading_across_pi():
    """Halfway between 179 and -179 degrees is 180, not 0; and a pose added since a lookup
    is seen by the next one (the arrays are built once per pose)."""
    h = PoseHistory(3.0)
    h.add(Odometry(0.0, 0.0, math.radians(179.0), 0.0, 0.0))
    h.add(Odometry(1.0, 0.0, math.radians(-179.0), 0.0, 1.0))
    mid = h.at(np.array([0.5]))[0]
    assert mid[0] == pytest.approx(0.5)
    assert math.cos(mid[2]) == pytest.approx(-1.0) and abs(math.sin(mid[2])) < 1e-9
    h.add(Odometry(2.0, 0.0, math.radians(-179.0), 0.0, 2.0))
    assert h.at(np.array([1.5]))[0][0] == pytest.approx(1.5)


def test_a_doorways_jambs_are_kept_apart_where_the_ring_sees_through_between_them():
    # Two jambs 45 degrees apart (indices 3 and 5) with the view through the door between
    # them: one obstacle to the trace law, as close minima always are, two in ``apart``.
    r = [4.0] * 16
    r[3], r[4], r[5] = 1.2, 3.0, 1.22
    r[11] = 2.9  # the far wall behind
    sensor = RingSensor()
    pts = ring_points(r)
    sensor.echo_points = lambda scan: pts  # the update's echoes, as a scan would give them
    scan = _scan([1.0] * 16, np.zeros(16))
    obs = sensor.update(scan, Odometry(0.0, 0.0, 0.0, 0.0, 0.0))
    near = [o for o in obs if o.distance_m < 2.0]
    assert len(near) == 1
    apart = [o for o in sensor.apart() or [] if o.distance_m < 2.0]
    assert [round(o.distance_m, 2) for o in apart] == [1.2, 1.22]
    # A reading between that is not 1.8 times deeper (a bend's vertex) keeps them one.
    r[4] = 1.6
    pts = ring_points(r)
    obs = sensor.update(scan, Odometry(0.1, 0.0, 0.0, 0.0, 0.0))
    assert len([o for o in sensor.apart() or obs if o.distance_m < 2.0]) == 1
    # With view_ratio 0 nothing is kept apart.
    r[4] = 3.0
    pts = ring_points(r)
    off = RingSensor(SensingParams(view_ratio=0.0))
    off.echo_points = lambda scan: pts
    obs = off.update(scan, Odometry(0.0, 0.0, 0.0, 0.0, 0.0))
    assert len([o for o in off.apart() or obs if o.distance_m < 2.0]) == 1

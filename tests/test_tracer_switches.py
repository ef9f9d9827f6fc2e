"""Two of the tracer's switches found through the CAN board's fast ring (off by default:
TracerParams says why): each does what it says on a case built by hand, and not when off."""

from __future__ import annotations

import math

import numpy as np
import pytest

from hal.types import Odometry, SonarScan
from tslam.core.sensing import RingSensor, SensingParams
from tslam.core.sweep import Sweep

N = 16


def _scan(ranges: list[float], stamp: float, yaw0: float = 0.0) -> SonarScan:
    yaw = yaw0 + np.arange(N) * 2 * math.pi / N
    return SonarScan(
        np.asarray(ranges, dtype=float), 0.23 * np.cos(yaw), 0.23 * np.sin(yaw), yaw,
        np.full(N, stamp), 0.15, 6.5, math.radians(12.5),
    )  # fmt: skip


def _odo(stamp: float, heading: float = 0.0) -> Odometry:
    return Odometry(0.0, 0.0, heading, heading, stamp)


def test_a_held_spike_does_not_confirm_its_neighbours_spike():
    walls = [1.0] * N
    first = list(walls)
    first[3] = 0.2  # an outlier: held back
    second = list(walls)
    second[3] = math.nan  # transducer 3 silent: its held lie is kept for hold_s
    second[4] = 0.19  # a second outlier beside it
    for no_support, expect_near in ((True, False), (False, True)):
        sensor = RingSensor(SensingParams(held_no_support=no_support))
        sensor.update(_scan(walls, 0.0), _odo(0.0))
        obs = sensor.update(_scan(first, 0.1), _odo(0.1))
        assert min(o.distance_m for o in obs) > 1.0
        obs = sensor.update(_scan(second, 0.2), _odo(0.2))
        assert (min(o.distance_m for o in obs) < 0.5) is expect_near


def test_a_sweep_in_the_odometry_frame_is_not_smeared_by_a_turning_body():
    # One wall 1.5 m away at odometry bearing 90 deg, seen while the body turns 30 deg:
    # in the body's frame its bearing wanders; in the odometry frame it holds still.
    fixed, body = Sweep(), Sweep()
    for k in range(30):
        heading = math.radians(k)  # the body turns 1 degree a reading
        ranges = [math.nan] * N
        yaw0 = math.radians(2.0 * k)  # the turret sweeps as well
        yaw = yaw0 + np.arange(N) * 2 * math.pi / N
        # The transducer pointing nearest the wall's normal hears it.
        want = math.radians(90.0) - heading
        i = int(np.argmin(np.abs(np.angle(np.exp(1j * (yaw - want))))))
        ranges[i] = 1.5 - 0.23
        scan = _scan(ranges, float(k), yaw0)
        fixed.add(scan, heading)
        body.add(scan)
    end = math.radians(29.0)
    got = fixed.obstacles(end)
    assert len(got) == 1
    assert math.degrees(got[0].bearing_rad) + 29.0 == pytest.approx(90.0, abs=4.0)
    smeared = body.obstacles()
    assert not smeared or abs(math.degrees(smeared[0].bearing_rad) - (90.0 - 29.0)) > 4.0


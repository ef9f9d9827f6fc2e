"""A contact is escaped away from where the base was going, even after the command that
drove into it was zeroed (fig13 seed 1 stood for 20 minutes backing into a wall behind it)."""

from __future__ import annotations

import numpy as np

from hal.interfaces import NOMAD200_LIMITS
from hal.types import DriveStatus, Odometry, SonarScan
from tslam.core.tracer import Behaviour, Tracer

CLEAR = DriveStatus(bumper=False, stall=False, motors_on=True, stamp_s=0.0)
PRESSED = DriveStatus(bumper=True, stall=True, motors_on=True, stamp_s=0.0)


def silent_scan(now: float) -> SonarScan:
    n = 16
    yaw = np.linspace(0.0, 2 * np.pi, n, endpoint=False)
    return SonarScan(
        np.full(n, np.nan), 0.2 * np.cos(yaw), 0.2 * np.sin(yaw), yaw, np.full(n, now),
        0.15, 6.5, 0.2,
    )  # fmt: skip


def test_backing_into_something_is_escaped_forwards():
    tracer = Tracer(NOMAD200_LIMITS)
    odo = Odometry(0.0, 0.0, 0.0, 0.0, 0.0)
    now = 0.0
    tracer.step(silent_scan(now), odo, PRESSED, now)  # touched while driving forwards ...
    first, _ = tracer.step(silent_scan(now), odo, PRESSED, now)
    assert tracer.s.behaviour is Behaviour.BACKOFF and first.v_mps < 0.0  # ... so back off
    # The wall it backs into stops it; the bounded backoff ends, and the base stands.
    while tracer.s.behaviour is Behaviour.BACKOFF:
        now += 0.1
        tracer.step(silent_scan(now), odo, CLEAR, now)
        assert now < 60.0
    stand, _ = tracer.step(silent_scan(now), odo, CLEAR, now)
    assert stand.v_mps == 0.0
    # Still pressed: the way out is forwards, away from what it backed into.
    now += 0.1
    tracer.step(silent_scan(now), odo, PRESSED, now)
    out, _ = tracer.step(silent_scan(now), odo, PRESSED, now)
    assert tracer.s.behaviour is Behaviour.BACKOFF and out.v_mps > 0.0

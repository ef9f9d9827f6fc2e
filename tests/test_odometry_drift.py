"""Dead reckoning drifts mostly in heading, by level, reproducibly."""

from __future__ import annotations

import math

import numpy as np
import pytest

from sim_backend.odometry_model import DeadReckoning, DriftParams


def drive_loops(level: str, seed: int, total_m: float = 300.0) -> tuple[float, float, float]:
    """A fig14-sized run of straight legs and right-angle turns; returns the final position
    error, the heading error (rad) and the worst relative error of a straight leg's length."""
    dr = DeadReckoning(0.0, DriftParams.level(level), np.random.default_rng(seed))
    x = y = th = 0.0
    d = 0.0
    legs = [8.0, 5.0, 8.0, 5.0, 3.0, 6.0, 3.0, 6.0]
    worst_leg = 0.0
    k = 0
    while d < total_m:
        length = legs[k % len(legs)]
        k += 1
        d0 = dr.distance
        for _ in range(int(length / 0.02)):
            x += 0.02 * math.cos(th)
            y += 0.02 * math.sin(th)
            dr.update(0.02, 0.0)
            d += 0.02
        worst_leg = max(worst_leg, abs((dr.distance - d0) - length) / length)
        turn = math.pi / 2 if k % 3 else -math.pi / 2
        for _ in range(50):
            dr.update(0.0, turn / 50)
        th += turn
    return math.hypot(dr.x - x, dr.y - y), dr.heading - th, worst_leg


def test_no_drift_is_exact():
    err, head, leg = drive_loops("none", 0)
    assert err < 1e-9 and abs(head) < 1e-9 and leg < 1e-9


def test_paper_level_accrues_several_metres_over_a_fig14_sized_run():
    errors = [drive_loops("paper", s)[0] for s in range(10)]
    assert 1.5 < float(np.median(errors)) < 8.0
    assert max(errors) > 3.0  # the paper saw "over 10 ft"


def test_heading_dominates_and_lengths_stay_good():
    for s in range(5):
        leg = drive_loops("paper", s)[2]
        # An edge's length is still measurable: within 3 % over a straight leg.
        assert leg < 0.03
    heads = [abs(drive_loops("paper", s)[1]) for s in range(10)]
    assert np.median(heads) > math.radians(5.0)


def test_severe_is_worse_than_paper():
    paper = np.median([drive_loops("paper", s)[0] for s in range(8)])
    severe = np.median([drive_loops("severe", s)[0] for s in range(8)])
    assert severe > 2.0 * paper


def test_seed_fixes_the_drift():
    assert drive_loops("paper", 3, 60.0) == drive_loops("paper", 3, 60.0)
    assert drive_loops("paper", 3, 60.0) != drive_loops("paper", 4, 60.0)


def test_unknown_level_is_refused():
    with pytest.raises(ValueError, match="unknown drift level 'bad'"):
        DriftParams.level("bad")

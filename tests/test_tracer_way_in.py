"""The way in as a departure of its own is read from a straight trail only.

A meet point's sweep can miss the edge the robot came in by (office:1's room, 2.9 m from its
door: ``test_tracer_room_door.py``), so a way in far from every departure seen is added as
one. The way in is the chord back to where the robot was 1 m off. Where the trail bent, that
chord is no edge's direction: fig14 seed 1 came back to the 0.53 m pair of true meet points 6
and 7 along a trail 1.41 times its chord, 41 degrees off the edge it had come by, and the
meet point, read with a fourth edge, had no look-alike and went into the map twice.
"""

from __future__ import annotations

import math
from dataclasses import replace

import pytest

from hal.interfaces import NOMAD200_LIMITS
from hal.types import Odometry
from tslam.core.tracer import Tracer, TracerParams
from tslam.programs.sim_cmd import explore, report


def _tracer_along(points: list[tuple[float, float]]) -> tuple[Tracer, Odometry]:
    """A tracer whose trail is ``points``, standing at the last one."""
    tracer = Tracer(NOMAD200_LIMITS, TracerParams())
    travelled = 0.0
    for k, (x, y) in enumerate(points):
        if k:
            travelled += math.dist(points[k - 1], (x, y))
        tracer.s.trail.append((travelled, x, y))
    x, y = points[-1]
    return tracer, Odometry(x, y, 0.0, 0.0, 0.0, travelled)


def _line(x0: float, y0: float, bearing: float, length: float) -> list[tuple[float, float]]:
    # 3 cm apart: the tracer keeps 64 points, one per cycle that moved 2 cm or more.
    c, s = 0.03 * math.cos(bearing), 0.03 * math.sin(bearing)
    return [(x0 + k * c, y0 + k * s) for k in range(round(length / 0.03) + 1)]


def test_a_straight_trail_gives_the_way_back():
    tracer, odo = _tracer_along(_line(0.0, 0.0, math.radians(30.0), 1.2))
    way_in = tracer._unseen_way_in(odo)
    assert way_in is not None
    assert abs(math.degrees(way_in) - 210.0) < 1.0


@pytest.mark.parametrize("turn_deg, trusted", [(45.0, True), (80.0, False), (90.0, False)])
def test_a_trail_bent_within_the_last_metre_is_trusted_up_to_way_in_bent(turn_deg, trusted):
    # 1 m on, then 0.6 m after the turn: the chord of 1 m spans the turn.
    first = _line(0.0, 0.0, 0.0, 1.0)
    second = _line(*first[-1], math.radians(turn_deg), 0.6)[1:]
    tracer, odo = _tracer_along(first + second)
    assert (tracer._unseen_way_in(odo) is not None) is trusted
    tracer.p = replace(TracerParams(), way_in_bent=2.0)
    assert tracer._unseen_way_in(odo) is not None  # the chord, were it trusted


def test_fig14_seed_1_keeps_the_close_pair_one_place():
    """Seed 1 at drift paper: with the bend ignored, meet point 6 is read with four edges
    at 1325 s and mapped twice; with it, no copy by 1400 s."""
    runs = {}
    for bent in (TracerParams().way_in_bent, math.inf):
        run = explore("fig14", 1, "paper", 1400.0, progress=False,
                      tracer_params=replace(TracerParams(), way_in_bent=bent))  # fmt: skip
        runs[bent] = report(run, "fig14", 1, "paper")
    kept, ignored = runs[TracerParams().way_in_bent], runs[math.inf]
    assert ignored["duplicate_nodes"] >= 1
    assert kept["duplicate_nodes"] == 0
    assert kept["false_merges"] == ignored["false_merges"] == 0

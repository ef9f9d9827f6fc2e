"""Past the node it expected, the robot is recognised one edge further on only where no
unexplored departure of the node passed could have led on instead.

fig15 seed 2 (stop 44's tracer): back from a corner's dead end the robot went through its
junction unhomed, along the aisle nobody had traced, to the next crossing; one edge up the
other aisle lay a crossing as far and alike, and the robot took itself to be there. Where it
really was, the map was built on as if it stood elsewhere, and a loop closure later merged
four crossings onto their neighbours 3.5 m away."""

from __future__ import annotations

import math

import pytest

from hal.interfaces import NOMAD200_LIMITS
from hal.types import Odometry
from tests.test_explorer_split import meet
from tslam.core.explorer import Explorer, ExplorerParams

R = math.radians


def past_the_junction(params: ExplorerParams, east_known: bool) -> Explorer:
    """Junction W at (0, 0) (east unexplored unless ``east_known``, north to crossing X 3.4 m
    up, south-west to a dead end 0.6 m off); the robot, back from the dead end, homes 4.0 m
    on at a crossing read as X would be read come at from W."""
    ex = Explorer(NOMAD200_LIMITS, params=params)
    m = ex.map
    w = m.add_meet(0.9, [R(0), R(90), R(225)], (0.0, 0.0))
    x = m.add_meet(0.9, [R(30), R(150), R(270)], (0.0, 3.4))
    d = m.add_boundary(0.4, (-0.42, -0.42))
    m.connect(w, 1, x, 2, 3.4)
    m.connect(w, 2, d, 0, 0.6)
    if east_known:
        y = m.add_meet(0.9, [R(0), R(180), R(300)], (3.4, 0.0))
        m.connect(w, 0, y, 1, 3.4)
    ex._odo = Odometry(-0.42, -0.42, 0.0, 0.0, 10.0, 10.0)
    ex._leave(d, 0)
    ex._odo = Odometry(3.4, 0.0, 0.0, 0.0, 14.0, 14.0)
    # Come in from the west (180), the others 120 and 240 degrees round: as X from W.
    ex._choose(meet(3.4, 0.0, [180, 300, 60], 180, 4.0))
    return ex


@pytest.mark.parametrize("known_only", [True, False])
def test_with_an_unexplored_way_on_the_crossing_one_edge_further_is_not_taken(known_only):
    ex = past_the_junction(ExplorerParams(further_known_only=known_only), east_known=False)
    further = [n.text for n in ex.notes if "one edge further" in n.text]
    if known_only:
        assert not further and ex.here != 2
    else:
        assert further == ["expected node 1, recognised node 2 one edge further"]
        assert ex.here == 2


def test_with_every_way_on_known_the_crossing_one_edge_further_is_recognised():
    # East traced to its own crossing: the length and the reading single out X.
    ex = past_the_junction(ExplorerParams(), east_known=True)
    assert [n.text for n in ex.notes] == ["expected node 1, recognised node 2 one edge further"]
    assert ex.here == 2

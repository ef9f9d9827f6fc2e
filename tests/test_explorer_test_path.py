"""Testing the hypotheses before exploring on (ExplorerParams.test_paths, keep_apart): an
arrival no hypothesis predicts ages them, and one that ages out takes its evidence with it
while its nodes stay in the map as copies (fig13 seed 2 at drift paper)."""

from __future__ import annotations

import math

import pytest

from hal.interfaces import NOMAD200_LIMITS
from tslam.core.explorer import Explorer, ExplorerParams
from tslam.core.localize import Hypothesis

DEPS = tuple(math.radians(a) for a in (90, 180, 330))  # no symmetry: one rotation fits


def _back_at_a_copy(**params: bool) -> tuple[Explorer, dict[str, int]]:
    """Old junctions a-b-c in a row (a's and c's other departures unexplored); the robot
    came back to a by an unexplored departure and traced x (a again) to y (b again): one
    confirmation. It stands at x, whose unexplored departures are a's unexplored ones."""
    ex = Explorer(NOMAD200_LIMITS, params=ExplorerParams(**params))
    m = ex.map
    a, b, c, x, y = (m.add_meet(1.0, DEPS, (0.0, 0.0)) for _ in range(5))
    m.connect(a, 2, b, 0, 3.0)
    m.connect(b, 1, c, 0, 4.0)
    m.connect(x, 2, y, 0, 3.05)
    ex.hyps.fragment.update({x, y})
    ex.hyps.live = [Hypothesis({x: (a, 0), y: (b, 0)}, confirmed=1)]
    return ex, {"a": a, "b": b, "c": c, "x": x, "y": y}


def test_with_nothing_to_test_here_the_robot_goes_where_a_departure_tests():
    ex, n = _back_at_a_copy()
    assert ex._separating_port(n["x"]) is None
    assert ex._separating_port(n["y"]) == 1  # b's departure 1 is traced: to c, 4 m
    assert ex._next_port(n["x"], 2) == 2  # back along the copy of a-b ...
    assert [s.node for s in ex.plan] == []  # ... one edge: y is next door
    assert ex._next_port(n["y"], 0) == 1  # ... and out by the departure that tests


def test_without_test_paths_the_robot_explores_on_from_here():
    ex, n = _back_at_a_copy(test_paths=False)
    assert ex._next_port(n["x"], 2) in (0, 1)  # a departure no hypothesis says anything of


@pytest.mark.parametrize("keep_apart", [True, False])
def test_a_merge_keeps_open_a_tested_hypothesis_about_other_nodes(keep_apart):
    """Merging one placement proves nothing about another part of the fragment placed
    elsewhere: that hypothesis stays open, renamed, with its evidence."""
    ex, n = _back_at_a_copy(keep_apart=keep_apart)
    m = ex.map
    d, e, u, v = (m.add_meet(1.5, DEPS, (0.0, 0.0)) for _ in range(4))
    m.connect(d, 2, e, 0, 6.0)
    m.connect(u, 2, v, 0, 6.1)
    ex.hyps.fragment.update({u, v})
    other = ex.hyps.live[0]
    proven = Hypothesis({u: (d, 0), v: (e, 0)}, confirmed=3)
    ex.hyps.live.append(proven)
    renamed = ex._merge(proven)
    assert renamed == {u: (d, 0), v: (e, 0)}
    if keep_apart:
        (kept,) = ex.hyps.live
        assert kept.mapping == other.mapping and kept.confirmed == 1
        assert ex.hyps.fragment == {n["x"], n["y"]}  # d and e are old places, not fragment
    else:
        assert not ex.hyps.live

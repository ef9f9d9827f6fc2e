"""A proven hypothesis is not held up by a rival that says nothing against it
(``Resolving._lead_apart``, ``_compatible``): in fig14 (seed 4 at drift paper, 6000 s) a
placement of the second lap of a loop on the mapped places, and of the third on the first,
and a placement of the third lap on the mapped places were both true, yet as rivals they
left 30 nodes unmerged."""

from __future__ import annotations

import math

from hal.interfaces import NOMAD200_LIMITS
from tslam.core.explorer import Explorer, ExplorerParams
from tslam.core.localize import Hypothesis

A_DEPS = [0, 120, 240]
B_DEPS = [0, 100, 230]
C_DEPS = [0, 90, 200]


def _rad(degs: list[float]) -> tuple[float, ...]:
    return tuple(math.radians(d) for d in degs)


def _map(params: ExplorerParams | None = None) -> tuple[Explorer, dict[str, int]]:
    """Old A - B and C; the fragment X - Y - Z, X and Y read like A and B, Z like C."""
    ex = Explorer(NOMAD200_LIMITS, params=params)
    n = {}
    n["a"] = ex.map.add_meet(1.0, _rad(A_DEPS), (0.0, 0.0))
    n["b"] = ex.map.add_meet(1.2, _rad(B_DEPS), (2.0, 0.0))
    ex.map.connect(n["a"], 0, n["b"], 1, 2.0)
    n["c"] = ex.map.add_meet(1.4, _rad(C_DEPS), (9.0, 0.0))
    n["x"] = ex.map.add_meet(1.0, _rad(A_DEPS), (0.1, 0.0))
    n["y"] = ex.map.add_meet(1.2, _rad(B_DEPS), (2.1, 0.0))
    ex.map.connect(n["x"], 0, n["y"], 1, 2.0)
    n["z"] = ex.map.add_meet(1.4, _rad(C_DEPS), (5.0, 0.0))
    ex.map.connect(n["y"], 0, n["z"], 1, 3.0)
    ex.hyps.fragment = {n["x"], n["y"], n["z"]}
    return ex, n


def _resolve_beside(
    rival: str, confirmed: int = 1, params: ExplorerParams | None = None
) -> tuple[Explorer, dict[str, int]]:
    """X = A, Y = B proven four times over, beside a rival placing ``rival`` on C."""
    ex, n = _map(params)
    h = Hypothesis({n["x"]: (n["a"], 0), n["y"]: (n["b"], 0)}, confirmed=4)
    ex.hyps.live = [h, Hypothesis({n[rival]: (n["c"], 0)}, confirmed=confirmed)]
    ex._resolve(n["z"])
    return ex, n


def test_a_rival_about_other_nodes_is_kept_open_and_the_proven_one_merged():
    ex, n = _resolve_beside("z")
    assert not ex.map.has_node(n["x"]) and not ex.map.has_node(n["y"])
    assert [x.mapping for x in ex.hyps.live] == [{n["z"]: (n["c"], 0)}]


def test_a_rival_that_places_a_node_elsewhere_holds_the_merge_up():
    ex, n = _resolve_beside("y")
    assert ex.map.has_node(n["x"]) and ex.map.has_node(n["y"])


def test_a_lap_onto_the_fragment_leaves_its_nodes_to_the_rival():
    ex, n = _map()
    h = Hypothesis({n["x"]: (n["a"], 0), n["y"]: (n["b"], 0)}, confirmed=4)
    lap = Hypothesis({n["x"]: (n["z"], 0)}, confirmed=1)
    assert ex._compatible(h, Hypothesis({n["y"]: (n["b"], 0)}, confirmed=1))  # agrees
    assert not ex._compatible(h, Hypothesis({n["y"]: (n["c"], 0)}, confirmed=1))
    # h places x on an old node; a rival placing x on a node of the fragment says otherwise.
    assert not ex._compatible(h, lap)
    # The other way round: h closing x onto the fragment leaves x's place to the rival.
    assert ex._compatible(lap, h)


def test_a_lap_that_ends_on_an_old_node_is_followed_there():
    # h closes y onto z and places z on C: in the end y is C. A rival with y on A says
    # otherwise; one with y on C agrees.
    ex, n = _map()
    h = Hypothesis({n["y"]: (n["z"], 0), n["z"]: (n["c"], 0)}, confirmed=4)
    assert not ex._compatible(h, Hypothesis({n["y"]: (n["a"], 0)}, confirmed=1))
    assert ex._compatible(h, Hypothesis({n["y"]: (n["c"], 0)}, confirmed=1))
    assert ex._compatible(h, Hypothesis({n["x"]: (n["a"], 0)}, confirmed=1))


def test_without_the_rule_a_rival_about_other_nodes_holds_the_merge_up():
    ex, n = _resolve_beside("z", params=ExplorerParams(merge_compatible=False))
    assert ex.map.has_node(n["x"]) and ex.map.has_node(n["y"])


def test_a_rival_with_as_much_support_holds_the_merge_up():
    ex, n = _resolve_beside("z", confirmed=4)
    assert ex.map.has_node(n["x"]) and ex.map.has_node(n["y"])

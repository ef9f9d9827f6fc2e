"""A dead end reached past the junction a hypothesis predicted, unhomed there: the hypothesis
is kept by the two edges' length (ExplorerParams.past_to_dead_end), and when the robot, back
from the dead end, homes at that junction and splits the edge there, the junction found
where the hypothesis put it confirms it (``past_found``). fig13 seed 2 went east from meet
point 7 past meet point 8 to its dead end, 3.2 m where meet point 8 was predicted at 2.0 m:
the true hypothesis was refuted there, and the building was mapped again."""

from __future__ import annotations

import math
from dataclasses import replace

import pytest

from hal.interfaces import NOMAD200_LIMITS
from tests.test_explorer_past import A_DEPS, M_DEPS, PAST, _add, _x_is_a_again
from tslam.core.explorer import Explorer, ExplorerParams
from tslam.core.tracer import BoundaryReached


def _a_m_dead_end(ex: Explorer) -> tuple[int, int, int]:
    """A - M east (2 m), and M's branch north to a dead end D (1.3 m)."""
    a, m = _add(ex, 1.0, A_DEPS, 0.0), _add(ex, 1.3, M_DEPS, 2.0)
    d = ex.map.add_boundary(0.4, (2.0, 1.3))
    ex.map.connect(a, 0, m, 2, 2.0)
    ex.map.connect(m, 1, d, 0, 1.3)
    return a, m, d


def _past_m_to_the_dead_end(params: ExplorerParams, length: float):
    ex = Explorer(NOMAD200_LIMITS, params=params)
    a, m, d = _a_m_dead_end(ex)
    x, h = _x_is_a_again(ex, a)
    ex._on_boundary(BoundaryReached(0.0, 22.0, 1.3, 0.4, length))
    (b,) = [n.id for n in ex.map.nodes() if n.kind == "boundary" and n.id != d]
    return ex, h, (a, m, d, x, b)


def test_a_dead_end_as_far_as_the_junction_and_its_branch_keeps_the_hypothesis():
    ex, h, (_a, _m, d, _x, b) = _past_m_to_the_dead_end(PAST, 3.25)
    (edge,) = [e.id for e in ex.map.edges() if b in (e.u, e.v)]
    assert ex.hyps.live == [h]
    assert h.mapping[b] == (d, 0) and h.cuts == {edge} and h.dead_ends == 0


@pytest.mark.parametrize(
    "params, length",
    [(replace(PAST, past_to_dead_end=False), 3.25), (PAST, 4.5), (PAST, 2.0)],
    ids=["switched off", "further than the branch", "as far as the junction"],
)
def test_otherwise_the_dead_end_refutes_it(params, length):
    ex, h, _ = _past_m_to_the_dead_end(params, length)
    assert h not in ex.hyps.live


def test_the_junction_found_on_that_edge_confirms_the_hypothesis():
    ex, h, (_a, m, _d, _x, b) = _past_m_to_the_dead_end(PAST, 3.25)
    (e,) = h.cuts
    confirmed = h.confirmed
    # Back from the dead end the robot homes at M, 1.3 m on, arriving from the north.
    n = _add(ex, 1.3, M_DEPS, 22.0)
    ex.map.split_edge(e, b, 0, n, 1, 2, 1.3)
    assert ex._found_past(e, b, 0, n, 1, 1.3) == [h]
    assert h.mapping[n] == (m, 0) and not h.cuts and h.confirmed == confirmed + 1
    # Only where the junction is as far as the hypothesis put it.
    ex2, h2, (_a2, _m2, _d2, _x2, b2) = _past_m_to_the_dead_end(PAST, 3.25)
    (e2,) = h2.cuts
    n2 = _add(ex2, 1.3, M_DEPS, 22.0)
    ex2.map.split_edge(e2, b2, 0, n2, 1, 2, 2.2)
    assert ex2._found_past(e2, b2, 0, n2, 1, 2.2) == [] and h2.cuts == {e2}
    assert math.isclose(ex2.map.edge(ex2.map.node(n2).ports[1]).length_m, 2.2)

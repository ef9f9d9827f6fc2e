"""A hypothesis follows the robot along a departure of a misread node (ExplorerParams.
unsure_follow): the arrival, found where and as it predicted, is no evidence (the robot may
have gone along another departure to a look-alike as far), but the new node is placed, so
the edges after it test the hypothesis. Before, it said nothing there and aged out: fig13
seed 56 read the 0.29 m pair with two of its edges as one, left it east and reached meet
point 9 as predicted, and the true hypothesis could predict nothing from there on."""

from __future__ import annotations

from dataclasses import replace

import pytest

from hal.interfaces import NOMAD200_LIMITS
from tests.test_explorer_past import M_DEPS, PAST, _a_m_b, _x_is_a_again, meet
from tslam.core.explorer import Explorer


@pytest.mark.parametrize("follow", [True, False])
def test_an_arrival_after_a_misread_node_is_placed_but_not_counted(follow):
    ex = Explorer(NOMAD200_LIMITS, params=replace(PAST, unsure_follow=follow))
    a, m, _b = _a_m_b(ex)
    _x, h = _x_is_a_again(ex, a)
    confirmed = h.confirmed
    ex.unsure_departure = True  # X was read with an edge fewer: its departure is unsure
    node, _ = ex._arrive(meet(22.0, 0.0, M_DEPS, 180, 2.0, 1.3))
    assert ex.hyps.live[0] is h and h.confirmed == confirmed
    assert (h.mapping.get(node) == (m, 0)) is follow
    assert h.silent_arrivals == (0 if follow else 1)


def test_an_arrival_that_does_not_fit_is_not_placed_and_refutes_nothing():
    ex = Explorer(NOMAD200_LIMITS, params=PAST)
    a, _m, _b = _a_m_b(ex)
    _x, h = _x_is_a_again(ex, a)
    ex.unsure_departure = True
    node, _ = ex._arrive(meet(25.0, 0.0, M_DEPS, 180, 5.0, 1.3))  # 5 m: not M
    assert h in ex.hyps.live and node not in h.mapping

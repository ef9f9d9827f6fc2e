"""A fragment may close onto itself: hypotheses that say so compete with those that place
the fragment on old nodes by a margin of evidence, are not tested by moves of their own, and
outlive a merge of the other kind renamed (``Explorer._loops_apart``)."""

from __future__ import annotations

import math

from hal.interfaces import NOMAD200_LIMITS
from tslam.core.explorer import Explorer
from tslam.core.localize import Hypotheses, Hypothesis, separating_port

T = (0.0, 2.0 * math.pi / 3.0, 4.0 * math.pi / 3.0)


def _explorer(n: int) -> Explorer:
    ex = Explorer(NOMAD200_LIMITS)
    for i in range(n):
        ex.map.add_meet(1.0, T, (float(i), 0.0))
    return ex


def test_a_proven_loop_goes_ahead_of_placements_two_confirmations_behind():
    ex = _explorer(4)
    ex.hyps.fragment = {3, 4}
    loop = Hypothesis({4: (3, 0)}, confirmed=3)
    place = Hypothesis({4: (1, 0)}, confirmed=1)
    assert ex._loops_apart([loop, place], 2) == ([loop], [place], False)
    place.confirmed = 2  # one behind: neither goes ahead, and no merge is made
    assert ex._loops_apart([loop, place], 2) == ([place], [], True)
    place.confirmed, loop.confirmed = 4, 2  # the placement ahead: the loop ends with it
    assert ex._loops_apart([loop, place], 2) == ([place], [], False)
    assert ex._loops_apart([place], 2) == ([place], [], False)


def test_a_placement_kept_through_a_loop_merge_is_renamed_or_dropped():
    ex = _explorer(5)
    # Node 4 merged into node 3, its port 0 being 3's port 1.
    renamed = {4: (3, 1)}
    ex.map.remove_node(4)
    kept = ex._renamed_hypothesis(Hypothesis({4: (1, 0), 5: (2, 2)}, confirmed=1), renamed)
    assert kept is not None and kept.mapping == {3: (1, 2), 5: (2, 2)} and kept.confirmed == 1
    # Two of its nodes became one, or one its own old node: nothing the map can hold.
    assert ex._renamed_hypothesis(Hypothesis({4: (1, 0), 3: (2, 0)}), renamed) is None
    assert ex._renamed_hypothesis(Hypothesis({4: (3, 0)}), renamed) is None


def test_a_loop_asks_for_no_move_of_its_own():
    ex = _explorer(3)
    ex.map.connect(1, 0, 2, 0, 3.0)  # old node 1 has an edge where fragment node 3 has none
    ex.hyps.fragment = {3}
    ex.hyps.live = [Hypothesis({3: (1, 0)}, confirmed=1)]
    assert ex._separating_port(3) == 0  # a placement is tested by leaving by port 0
    ex.hyps.fragment = {1, 3}  # ... but node 1 is the fragment's own: a loop
    assert separating_port(ex.map, Hypotheses(ex.hyps.fragment, ex.hyps.live), 3) == 0
    assert ex._separating_port(3) is None

"""A merge that makes an edge a loop needs dead reckoning to agree that the robot came back to
where it left: over one edge it is good to decimetres.

fig1 seed 11 at drift ``paper`` (with stop 26's tracer): the robot mapped the room at one end
of the building, left it along the 3.9 m edge to its mirror image and mapped that. Two nodes and
two dead ends each alike, headings alike (a mirror across the edge's normal keeps them), and
only one look-alike: the second room was merged onto the first, the edge between them a loop
back to the room it left, although dead reckoning had them 3.6 m apart.
"""

from __future__ import annotations

from hal.interfaces import NOMAD200_LIMITS
from tslam.core.explorer import Explorer
from tslam.core.localize import Hypothesis
from tslam.core.topomap import TopoMap

DEPARTURES = (0.0, 1.6, 3.1)


def _two_rooms() -> tuple[TopoMap, int, int, int]:
    """A junction and its look-alike one 3.9 m edge away."""
    m = TopoMap()
    a = m.add_meet(1.7, DEPARTURES, (0.0, 0.0))
    b = m.add_meet(1.7, DEPARTURES, (3.6, 0.0))
    e = m.connect(a, 0, b, 2, 3.9)
    return m, a, b, e


def test_a_merge_that_loops_an_edge_whose_ends_dead_reckoning_puts_apart_is_refused():
    m, a, b, e = _two_rooms()
    ex = Explorer(NOMAD200_LIMITS, tmap=m)
    ex.edge_gap[e] = 3.6
    h = Hypothesis({b: (a, 0)}, confirmed=3)
    assert ex._false_loop(h) == (e, 3.6)
    assert ex._merge(h) == {}
    assert m.has_node(a) and m.has_node(b)
    assert any(n.text.startswith("merge refused: it makes edge") for n in ex.notes)


def test_a_loop_whose_ends_meet_is_merged():
    m, a, b, e = _two_rooms()
    ex = Explorer(NOMAD200_LIMITS, tmap=m)
    ex.edge_gap[e] = 0.4  # left and came back: a real loop round an island
    h = Hypothesis({b: (a, 0)}, confirmed=3)
    assert ex._false_loop(h) is None
    assert ex._merge(h) != {}
    assert not m.has_node(b)

"""Before a merge, the fragment's tested part is placed on the map everywhere it fits
(tslam.core.placements): a second fit is a rival hypothesis, not a proof."""

from __future__ import annotations

import math

from tslam.core.localize import Hypothesis, Tolerances
from tslam.core.placements import other_placements
from tslam.core.topomap import TopoMap

Y = tuple(math.radians(a) for a in (90, 180, 330))  # no symmetry: one rotation fits


def wing(tmap: TopoMap, length: float) -> tuple[int, int]:
    """Two look-alike junctions joined by an edge of ``length`` (port 2 to port 0)."""
    a = tmap.add_meet(1.0, Y, (0.0, 0.0))
    b = tmap.add_meet(1.0, Y, (0.0, 0.0))
    tmap.connect(a, 2, b, 0, length)
    return a, b


def test_a_fragment_that_fits_two_wings_has_a_rival():
    tmap = TopoMap()
    a1, b1 = wing(tmap, 3.0)
    a2, b2 = wing(tmap, 3.1)
    x, y = wing(tmap, 3.05)  # the fragment, just traced
    h = Hypothesis({x: (a1, 0), y: (b1, 0)}, confirmed=2)
    rivals, own_fits = other_placements(tmap, h, Tolerances())
    assert own_fits
    assert rivals == [{x: (a2, 0), y: (b2, 0)}]


def test_a_wing_of_another_length_is_no_rival():
    tmap = TopoMap()
    a1, b1 = wing(tmap, 3.0)
    wing(tmap, 5.0)
    x, y = wing(tmap, 3.05)
    rivals, own_fits = other_placements(tmap, Hypothesis({x: (a1, 0), y: (b1, 0)}), Tolerances())
    assert own_fits and rivals == []


def test_an_edge_that_only_bounds_the_mapped_one_does_not_prove_the_hypothesis():
    # Traced with a detour, 8 m matched the 3 m edge only as a lower bound.
    tmap = TopoMap()
    a1, b1 = wing(tmap, 3.0)
    x, y = wing(tmap, 8.0)
    rivals, own_fits = other_placements(tmap, Hypothesis({x: (a1, 0), y: (b1, 0)}), Tolerances())
    assert not own_fits and rivals == []


def test_a_dead_end_reached_deeper_in_fits_with_the_depth_allowed():
    """The edge into a dead end ends where the boundary rule stopped the robot: nearer the
    walls, deeper in. A placement the prediction accepted (``Boundaries._dead_end_tol``)
    must fit here too, or a proven hypothesis waits for ever (fig14 seed 1)."""
    tmap = TopoMap()
    a1 = tmap.add_meet(1.0, Y, (0.0, 0.0))
    b1 = tmap.add_boundary(0.44, (0.0, 0.0))
    tmap.connect(a1, 0, b1, 0, 0.36)
    x = tmap.add_meet(1.0, Y, (0.0, 0.0))
    y = tmap.add_boundary(0.29, (0.0, 0.0))
    tmap.connect(x, 0, y, 0, 0.67)
    h = Hypothesis({x: (a1, 0), y: (b1, 0)}, dead_ends=1)
    assert other_placements(tmap, h, Tolerances()) == ([], False)
    assert other_placements(tmap, h, Tolerances(), dead_end_depth=1.5) == ([], True)


def test_a_search_too_large_for_its_budget_proves_nothing():
    tmap = TopoMap()
    for _ in range(30):
        wing(tmap, 3.0)
    x, y = wing(tmap, 3.0)
    h = Hypothesis({x: (0, 0), y: (1, 0)})
    assert other_placements(tmap, h, Tolerances(), limit=100, budget=20) is None


def chain(tmap: TopoMap, first: float | None, second: float | None) -> tuple[int, int, int]:
    """Three look-alike junctions a, b, c: a's port 2 to b's port 0 by an edge of length
    ``first``, b's port 1 to c's port 0 by one of ``second``; None leaves both ports
    unexplored."""
    a, b, c = (tmap.add_meet(1.0, Y, (0.0, 0.0)) for _ in range(3))
    if first is not None:
        tmap.connect(a, 2, b, 0, first)
    if second is not None:
        tmap.connect(b, 1, c, 0, second)
    return a, b, c


def test_a_place_mapped_with_an_edge_untraced_is_a_rival_with_open_edges():
    # fig15 severe seed 2: the corner the robot was back at had edges never traced, and
    # the fragment fit only a rotated corner mapped whole.
    tmap = TopoMap()
    a1, b1, c1 = chain(tmap, 3.0, 4.0)
    a2, b2, c2 = chain(tmap, 3.0, None)
    x, y, z = chain(tmap, 3.05, 4.05)
    h = Hypothesis({x: (a1, 0), y: (b1, 0), z: (c1, 0)}, confirmed=2)
    assert other_placements(tmap, h, Tolerances()) == ([], True)
    rivals, own_fits = other_placements(tmap, h, Tolerances(), open_edges=True)
    assert own_fits
    assert {x: (a2, 0), y: (b2, 0), z: (c2, 0)} in rivals
    # ... and so is any look-alike left with that departure unexplored: nothing says b2's
    # untraced edge does not lead there.
    assert {x: (a2, 0), y: (b2, 0), z: (a1, 0)} in rivals


def test_an_open_edge_needs_both_departures_unexplored():
    tmap = TopoMap()
    a1, b1, c1 = chain(tmap, 3.0, 4.0)
    _a2, _b2, c2 = chain(tmap, 3.0, None)
    elsewhere = tmap.add_meet(1.0, Y, (0.0, 0.0))
    tmap.connect(elsewhere, 2, c2, 0, 6.0)  # c2's departure is explored, to another place
    x, y, z = chain(tmap, 3.05, 4.05)
    h = Hypothesis({x: (a1, 0), y: (b1, 0), z: (c1, 0)}, confirmed=2)
    search = other_placements(tmap, h, Tolerances(), open_edges=True)
    assert search is not None
    assert all(r[z] != (c2, 0) for r in search[0])


def test_a_placement_on_open_edges_alone_is_no_rival():
    tmap = TopoMap()
    a1, b1, c1 = chain(tmap, 3.0, 4.0)
    chain(tmap, None, None)  # three look-alikes, nothing traced between them
    x, y, z = chain(tmap, 3.05, 4.05)
    h = Hypothesis({x: (a1, 0), y: (b1, 0), z: (c1, 0)}, confirmed=2)
    assert other_placements(tmap, h, Tolerances(), open_edges=True) == ([], True)


def test_a_single_node_fragment_fits_where_it_looks_alike_with_open_edges():
    tmap = TopoMap()
    a1, _, _ = chain(tmap, 3.0, 4.0)
    x = tmap.add_meet(1.0, Y, (0.0, 0.0))
    search = other_placements(tmap, Hypothesis({x: (a1, 0)}), Tolerances(), open_edges=True)
    assert search is not None and search[1]

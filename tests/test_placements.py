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


def test_a_search_too_large_for_its_budget_proves_nothing():
    tmap = TopoMap()
    for _ in range(30):
        wing(tmap, 3.0)
    x, y = wing(tmap, 3.0)
    h = Hypothesis({x: (0, 0), y: (1, 0)})
    assert other_placements(tmap, h, Tolerances(), limit=100, budget=20) is None

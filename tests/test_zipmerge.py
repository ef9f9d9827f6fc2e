"""A hypothesis made true in a copy of the map says what else it claims (tslam.core.zipmerge)."""

from __future__ import annotations

import pytest

from tslam.core.topomap import Likeness, MapError, TopoMap
from tslam.core.zipmerge import implies, merge_mapping

ALIKE = Likeness(0.15, 0.44, 0.25, 0.08)


def two_copies(second_length: float = 3.0) -> tuple[TopoMap, list[int]]:
    """Junctions a-b 3 m apart, and a copy a2-b2 of them; each has departures to explore."""
    m = TopoMap()
    deps = (0.0, 2.1, 4.2)
    a, b, a2, b2 = (m.add_meet(1.2, deps, (x, 0.0)) for x in (0.0, 3.0, 20.0, 23.0))
    m.connect(a, 0, b, 1, 3.0)
    m.connect(a2, 0, b2, 1, second_length)
    return m, [a, b, a2, b2]


def test_merging_one_node_of_a_copy_zips_the_rest_and_implies_it():
    m, (a, b, a2, b2) = two_copies()
    trial = m.copy()
    renamed = merge_mapping(trial, {a2: (a, 0)}, ALIKE)
    assert renamed == {a2: (a, 0), b2: (b, 0)}
    assert len(trial.nodes()) == 2 and len(m.nodes()) == 4  # the copy only
    assert implies(trial, renamed, {b2: (b, 0)})  # what the zip made true
    assert not implies(trial, renamed, {b2: (b, 1)})  # ... under another rotation: no
    assert not implies(trial, renamed, {b2: (a, 0)})
    assert not implies(m, {}, {b2: (b, 0)})  # nothing merged, nothing implied


def test_a_merge_the_map_contradicts_raises():
    m, (a, _, a2, _) = two_copies(second_length=6.0)
    with pytest.raises(MapError):
        merge_mapping(m.copy(), {a2: (a, 0)}, ALIKE)

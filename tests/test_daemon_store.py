"""The daemon stores the settled map: what the robot is still testing a look-alike for is left
out until the question is settled, and saved then, even when settling it changed no node."""

from __future__ import annotations

from hal.interfaces import NOMAD200_LIMITS
from tslam.core.explorer import Explorer
from tslam.core.localize import Hypothesis
from tslam.core.topomap import TopoMap
from tslam.daemon.store import Store
from tslam.programs.map_files import load_map

DEPS = (0.0, 2.1, 4.2)


def _explorer_testing_a_look_alike() -> Explorer:
    """Nodes 1 and 2 joined by an edge, node 3 found from 2 and looking like 1 (one hypothesis
    open: 3 is 1), and node 4, reached off the graph, with no edge yet."""
    m = TopoMap()
    a, b, c = (m.add_meet(1.0, DEPS, pose=(x, 0.0)) for x in (0.0, 3.0, 6.0))
    m.connect(a, 0, b, 1, 3.0)
    m.connect(b, 0, c, 1, 3.0)
    ex = Explorer(NOMAD200_LIMITS, tmap=m)
    m.add_meet(1.0, DEPS, pose=(9.0, 0.0))
    ex.hyps.fragment.add(c)
    ex.hyps.live.append(Hypothesis({c: (a, 0)}))
    return ex


def _stored(store: Store) -> tuple[set[int], int]:
    m = load_map(store.map_path)
    return {n.id for n in m.nodes()}, len(m.edges())


def test_the_settled_map_leaves_out_the_open_question_and_edgeless_nodes(tmp_path):
    ex = _explorer_testing_a_look_alike()
    store = Store(tmp_path)
    assert store.save_settled(ex)
    assert _stored(store) == ({1, 2}, 1)
    assert len(ex.map.nodes()) == 4  # the explorer's own map keeps everything


def test_a_question_settled_without_a_map_change_is_saved_then(tmp_path):
    ex = _explorer_testing_a_look_alike()
    store = Store(tmp_path)
    store.save_settled(ex)
    assert not store.save_settled(ex, changed=False)  # nothing new: no write
    ex.hyps.clear()  # the look-alike given up on: node 3 is a new place
    assert store.save_settled(ex, changed=False)
    assert _stored(store) == ({1, 2, 3}, 2)

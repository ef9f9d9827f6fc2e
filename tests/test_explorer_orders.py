"""Operators' orders to the arbiter (the daemon's goto, explore, stop), on a true GVG walked
without a simulator: a robot sent to a node arrives there along the graph and holds."""

from __future__ import annotations

import math

import networkx as nx
import pytest

from hal.interfaces import NOMAD200_LIMITS
from hal.types import Odometry
from sim_backend.ground_truth import compute_gvg
from sim_backend.world_files import load_world
from tests.graph_walk import from_ground_truth, walk
from tslam.core.explorer import Explorer, Mode

TAU = 2 * math.pi


def explored(world: str):
    graph = from_ground_truth(compute_gvg(load_world(world)))
    ex = Explorer(NOMAD200_LIMITS)
    start = next(n for n, v in graph.nodes.items() if v[0] == "meet")
    visited = walk(graph, ex, start, max_arrivals=400, noise=0.0, seed=2, drift_deg_per_edge=0)
    assert ex.done and ex.held
    return graph, ex, visited[-1]


def send(graph, ex: Explorer, at: str, order) -> tuple[object, list[str]]:
    """Give ``order`` to a robot held at true node ``at``; walk it until it holds again."""
    departed: list[float] = []
    ex.tracer.depart = lambda direction, odo: departed.append(direction)
    ex._odo = Odometry(0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
    answer = order(ex)
    if not departed:
        return answer, [at]
    deps = graph.nodes[at][2]
    port = min(
        range(len(deps)), key=lambda i: abs((deps[i] - departed[0] + math.pi) % TAU - math.pi)
    )
    nxt, nport, _ = graph.ends[(at, port)]
    return answer, walk(graph, ex, nxt, arrival_port=nport, max_arrivals=100, drift_deg_per_edge=0)


def truth_of(graph, name: str) -> tuple[float, float]:
    return graph.nodes[name][3], graph.nodes[name][4]


@pytest.mark.parametrize("world", ["fig1", "fig13"])
def test_goto_reaches_the_node_along_the_graph_and_holds(world):
    graph, ex, at = explored(world)
    here = ex.here
    meets = [n.id for n in ex.map.nodes() if n.kind == "meet" and n.id != here]
    dist = nx.single_source_dijkstra_path_length(ex.map.graph, here)
    target = max(meets, key=lambda n: dist[n])  # the farthest: several edges to follow
    answer, visited = send(graph, ex, at, lambda e: e.goto(target))
    assert answer is None
    assert ex.held and not ex.done and ex.mode is Mode.HOLD
    assert ex.here == target and ex.goal is None
    tx, ty = ex.map.node(target).truth
    vx, vy = truth_of(graph, visited[-1])
    assert math.hypot(tx - vx, ty - vy) < 1e-6  # it stands where the map says node target is
    assert len(visited) >= 2


def test_orders_that_cannot_be_carried_out_are_refused_with_a_reason():
    graph, ex, at = explored("fig1")
    assert "no node 999" in ex.goto(999)
    answer, _ = send(graph, ex, at, lambda e: e.explore())
    assert answer == "exploration is complete: no departure is left to explore"
    assert ex.done and ex.held
    lost = Explorer(NOMAD200_LIMITS, tmap=ex.map.copy())
    assert lost.goto(next(iter(n.id for n in ex.map.nodes()))) == (
        "the robot does not know which node it is at yet"
    )


def test_cancel_forgets_the_goal():
    _, ex, _ = explored("fig13")
    other = next(n.id for n in ex.map.nodes() if n.kind == "meet" and n.id != ex.here)
    ex.tracer.depart = lambda direction, odo: None
    ex._odo = Odometry(0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
    assert ex.goto(other) is None and ex.goal == other and not ex.held
    ex.cancel()
    assert ex.goal is None and ex.plan == []

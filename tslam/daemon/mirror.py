"""The map as the link carries it: a copy in link messages, diffed after each map change.

The monitor needs neither the core's change log nor its merge rules: a change message says
which nodes and edges now look how, and which are gone. The copy is what the queryable
serves, so the snapshot is built under a lock from the zenoh thread while the control loop
goes on.
"""

from __future__ import annotations

import threading

from tslam.core.explorer import Explorer
from tslam.core.topomap import Edge, Node
from tslam.link.schemas import EdgeMsg, MapChange, MapSnapshot, NodeMsg


def node_msg(n: Node, unexplored: int) -> NodeMsg:
    return NodeMsg(
        id=n.id, kind=n.kind, x=float(n.pose[0]), y=float(n.pose[1]),
        clearance_m=max(0.0, float(n.clearance_m)),
        degree=n.degree, unexplored=unexplored, ambiguous_with=sorted(n.ambiguous_with),
    )  # fmt: skip


def edge_msg(e: Edge) -> EdgeMsg:
    return EdgeMsg(id=e.id, u=e.u, v=e.v, length_m=max(0.0, float(e.length_m)))


class MapMirror:
    def __init__(self, robot: str, epoch: str, explorer: Explorer) -> None:
        self.robot, self.epoch = robot, epoch
        self._lock = threading.Lock()
        self.seq = 0
        self._version = explorer.map.version
        self._nodes, self._edges = _messages(explorer)

    def refresh(self, explorer: Explorer) -> MapChange | None:
        """The change since the last call, or None if the map is as it was."""
        tmap = explorer.map
        if tmap.version == self._version:
            return None
        ops = list(dict.fromkeys(c.op for c in tmap.changes_since(self._version)))
        nodes, edges = _messages(explorer)
        with self._lock:
            self.seq += 1
            change = MapChange(
                robot=self.robot, epoch=self.epoch, seq=self.seq, op=",".join(ops),
                upsert_nodes=[m for i, m in nodes.items() if self._nodes.get(i) != m],
                remove_nodes=sorted(set(self._nodes) - set(nodes)),
                upsert_edges=[m for i, m in edges.items() if self._edges.get(i) != m],
                remove_edges=sorted(set(self._edges) - set(edges)),
            )  # fmt: skip
            self._nodes, self._edges, self._version = nodes, edges, tmap.version
        return change

    def snapshot(self) -> MapSnapshot:
        with self._lock:
            return MapSnapshot(
                robot=self.robot, epoch=self.epoch, seq=self.seq,
                nodes=list(self._nodes.values()), edges=list(self._edges.values()),
            )  # fmt: skip


def _messages(explorer: Explorer) -> tuple[dict[int, NodeMsg], dict[int, EdgeMsg]]:
    todo: dict[int, int] = {}
    for n, _ in explorer.unexplored():
        todo[n] = todo.get(n, 0) + 1
    tmap = explorer.map
    nodes = {n.id: node_msg(n, todo.get(n.id, 0)) for n in tmap.nodes()}
    edges = {e.id: edge_msg(e) for e in tmap.edges()}
    return nodes, edges

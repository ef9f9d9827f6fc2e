"""A synthetic robot for the monitor's tests: a ``RobotLink`` with a small map, run as a process.

    python -m tests.monitor_fake_robot --robot r1 --listen PORT --nodes 4

It prints ``ready`` once its link is up. Commands act on its state as the daemon's would
(pause, resume, stop, explore, goto a node it has; goto another node is refused). Lines on
stdin change it from the test's side: ``add`` adds a node joined to the last one, ``behaviour
NAME`` sets the behaviour, ``quit`` ends it. Every change publishes the state, a map change
where the map changed, and an event.
"""

from __future__ import annotations

import argparse
import signal
import sys
import threading
import time

from tslam.link.config import LinkConfig
from tslam.link.robot import RobotLink
from tslam.link.schemas import (
    Command,
    CommandReply,
    EdgeMsg,
    EventMsg,
    MapChange,
    MapSnapshot,
    NodeMsg,
    RobotState,
)

EPOCH = "fake-epoch-1"


class FakeRobot:
    def __init__(self, robot: str, n_nodes: int) -> None:
        self.robot = robot
        self.lock = threading.Lock()
        self.nodes: dict[int, NodeMsg] = {}
        self.edges: dict[int, EdgeMsg] = {}
        self.seq = 0
        self.event_seq = 0
        self.behaviour = "trace_edge"
        self.mode = "explore"
        self.paused = False
        self.done = False
        self.goal: int | None = None
        self.link: RobotLink | None = None
        for _ in range(n_nodes):
            self._grow()
        # Node 1 looks like node 0: the page marks both ambiguous.
        if n_nodes >= 2:
            self.nodes[0] = NodeMsg(0, "meet", 0.0, 0.0, 1.0, 3, 1, [1])
            self.nodes[1] = NodeMsg(1, "meet", 3.0, 0.5, 1.0, 3, 1, [0])

    def _grow(self) -> tuple[NodeMsg, EdgeMsg | None]:
        i = len(self.nodes)
        node = NodeMsg(i, "meet" if i % 3 else "boundary", 3.0 * i, 0.5 * (i % 2), 1.0, 3, 1)
        self.nodes[i] = node
        edge = None
        if i > 0:
            edge = EdgeMsg(len(self.edges), i - 1, i, 3.0)
            self.edges[edge.id] = edge
        self.seq += 1
        return node, edge

    def snapshot(self) -> MapSnapshot:
        with self.lock:
            return MapSnapshot(
                self.robot, EPOCH, self.seq, list(self.nodes.values()), list(self.edges.values())
            )

    def state(self) -> RobotState:
        current = len(self.nodes) - 1 if self.nodes else None
        return RobotState(
            robot=self.robot, epoch=EPOCH, stamp_s=time.monotonic(), behaviour=self.behaviour,
            mode=self.mode, paused=self.paused, done=self.done, current_node=current,
            current_edge=None, goal_node=self.goal, x=3.0 * (current or 0), y=0.2, theta=0.5,
            hypotheses=["h1"], map_seq=self.seq, map_nodes=len(self.nodes),
            map_edges=len(self.edges), unexplored=sum(n.unexplored for n in self.nodes.values()),
            event_seq=self.event_seq,
        )  # fmt: skip

    def publish(self, kind: str, text: str, change: MapChange | None = None) -> None:
        assert self.link is not None
        if change is not None:
            self.link.publish_map_change(change)
        self.event_seq += 1
        self.link.publish_event(
            EventMsg(self.robot, EPOCH, self.event_seq, time.monotonic(), kind, text)
        )
        self.link.publish_state(self.state())

    def on_command(self, cmd: Command) -> CommandReply:
        with self.lock:
            if cmd.op == "goto" and cmd.node not in self.nodes:
                return CommandReply(cmd.id, False, f"no node {cmd.node} in the map")
            if cmd.op == "pause":
                self.paused, self.behaviour = True, "paused"
            elif cmd.op == "resume":
                self.paused, self.behaviour = False, "trace_edge"
            elif cmd.op == "stop":
                self.done, self.behaviour = True, "stopped"
            elif cmd.op == "explore":
                self.mode, self.goal = "explore", None
            elif cmd.op == "goto":
                self.mode, self.goal = "goto", cmd.node
            self.publish("command", f"{cmd.op} accepted")
        return CommandReply(cmd.id, True, "")

    def add_node(self) -> None:
        with self.lock:
            node, edge = self._grow()
            change = MapChange(
                self.robot, EPOCH, self.seq, "node_added", upsert_nodes=[node],
                upsert_edges=[edge] if edge else [],
            )  # fmt: skip
            self.publish("node", f"new node {node.id}", change)

    def set_behaviour(self, name: str) -> None:
        with self.lock:
            self.behaviour = name
            self.publish("behaviour", f"now {name}")


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--robot", default="r1")
    ap.add_argument("--listen", type=int, required=True)
    ap.add_argument("--nodes", type=int, default=4)
    ap.add_argument("--connect", type=int, action="append", default=[], help="peer ports")
    args = ap.parse_args()
    # SIGTERM from the test's cleanup must close the session (a hang at exit otherwise).
    signal.signal(signal.SIGTERM, signal.default_int_handler)
    fake = FakeRobot(args.robot, args.nodes)
    cfg = LinkConfig(
        mode="peer",
        listen=[f"tcp/127.0.0.1:{args.listen}"],
        connect=[f"tcp/127.0.0.1:{p}" for p in args.connect],
        lease_s=1.0,
        open_timeout_s=1.0,
    )
    try:
        with RobotLink(
            args.robot, cfg, EPOCH, snapshot=fake.snapshot, on_command=fake.on_command
        ) as link:
            fake.link = link
            with fake.lock:
                fake.publish("start", "fake robot up")
            print("ready", flush=True)
            for line in sys.stdin:
                words = line.split()
                if not words:
                    continue
                if words[0] == "add":
                    fake.add_node()
                elif words[0] == "behaviour":
                    fake.set_behaviour(words[1])
                elif words[0] == "quit":
                    break
                print("ok", flush=True)
    except KeyboardInterrupt:
        pass
    return 0


if __name__ == "__main__":
    sys.exit(main())

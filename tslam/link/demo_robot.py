"""A stand-in robot that serves a synthetic map through ``RobotLink``: for tests and benches.

``python -m tslam.link.demo_robot --robot r1 --listen tcp/127.0.0.1:7447 --nodes 100 --rate 20``

The map is a grid of meet points (30 to a row) joined left-right and up-down; it starts with
``--initial`` nodes and grows by ``--rate`` nodes a second up to ``--nodes``, each growth step
a numbered ``MapChange`` and an event. State goes out at ``--state-hz``, a 16-beam scan at
``--scan-hz``. Commands behave like the daemon's: ``pause`` stops the growth, ``resume`` and
``explore`` restart it, ``stop`` ends it, ``goto N`` is refused unless N is in the map. With
``--burst N`` an ``explore`` also starts N events at ``--burst-hz``, stamped with the system-wide
monotonic clock so that another process can time their delivery (``tslam bench link``).

Prints ``ready <epoch>`` on stdout once serving; exits 0 on SIGTERM or SIGINT.
"""

from __future__ import annotations

import argparse
import math
import sys
import threading
import time
import uuid

from tslam.link.config import LinkConfig
from tslam.link.errors import LinkError
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
    ScanMsg,
)
from tslam.stopflag import StopFlag, stop_on_signals

ROW = 30


class SyntheticMap:
    """A growing grid map whose every change is numbered; thread-safe."""

    def __init__(self, robot: str, epoch: str) -> None:
        self.robot, self.epoch = robot, epoch
        self.lock = threading.Lock()
        self.nodes: dict[int, NodeMsg] = {}
        self.edges: dict[int, EdgeMsg] = {}
        self.seq = 0

    def _node(self, i: int) -> NodeMsg:
        return NodeMsg(
            id=i,
            kind="meet",
            x=float(i % ROW),
            y=float(i // ROW),
            clearance_m=0.5 + 0.01 * (i % 50),
            degree=4,
            unexplored=2,
            ambiguous_with=[],
        )

    def grow(self) -> MapChange:
        """Add the next node and its edges to the map; the change describing it."""
        i = len(self.nodes)
        node = self._node(i)
        new_edges = []
        if i % ROW:
            new_edges.append(EdgeMsg(id=len(self.edges), u=i - 1, v=i, length_m=1.0))
            self.edges[new_edges[-1].id] = new_edges[-1]
        if i >= ROW:
            new_edges.append(EdgeMsg(id=len(self.edges), u=i - ROW, v=i, length_m=1.0))
            self.edges[new_edges[-1].id] = new_edges[-1]
        self.nodes[i] = node
        self.seq += 1
        return MapChange(
            robot=self.robot,
            epoch=self.epoch,
            seq=self.seq,
            op="node_added",
            upsert_nodes=[node],
            upsert_edges=new_edges,
        )

    def snapshot(self) -> MapSnapshot:
        with self.lock:
            return MapSnapshot(
                robot=self.robot,
                epoch=self.epoch,
                seq=self.seq,
                nodes=list(self.nodes.values()),
                edges=list(self.edges.values()),
            )


class DemoRobot:
    def __init__(self, args: argparse.Namespace, cfg: LinkConfig) -> None:
        self.args = args
        self.map = SyntheticMap(args.robot, args.epoch)
        for _ in range(args.initial):
            self.map.grow()
        self.paused = args.wait_explore
        self.done = False
        self.goal: int | None = None
        self.commands = 0
        self.burst_left = 0
        self.event_seq = 0
        self.stop = StopFlag()
        self.link = RobotLink(
            args.robot, cfg, args.epoch, snapshot=self.map.snapshot, on_command=self.on_command
        )
        self.event("start", f"serving {len(self.map.nodes)} nodes, epoch {args.epoch}")

    def on_command(self, cmd: Command) -> CommandReply:
        with self.map.lock:
            self.commands += 1
            if cmd.op == "pause":
                self.paused = True
            elif cmd.op in ("resume", "explore"):
                self.paused = self.done = False
                if cmd.op == "explore":
                    self.burst_left = self.args.burst
            elif cmd.op == "stop":
                self.paused, self.done = True, True
            elif cmd.op == "goto":
                if cmd.node not in self.map.nodes:
                    return CommandReply(cmd.id, False, f"no node {cmd.node} in the map")
                self.goal = cmd.node
        return CommandReply(cmd.id, True, f"{cmd.op} accepted")

    def event(self, kind: str, text: str) -> None:
        self.event_seq += 1
        self.link.publish_event(
            EventMsg(self.args.robot, self.args.epoch, self.event_seq, time.monotonic(), kind, text)
        )

    def state(self) -> RobotState:
        m = self.map
        n = len(m.nodes)
        return RobotState(
            robot=self.args.robot,
            epoch=self.args.epoch,
            stamp_s=time.monotonic(),
            behaviour="explore" if not self.paused else "idle",
            mode="stopped" if self.done else ("paused" if self.paused else "exploring"),
            paused=self.paused,
            done=self.done,
            current_node=n - 1 if n else None,
            current_edge=None,
            goal_node=self.goal,
            x=float((n - 1) % ROW) if n else 0.0,
            y=float((n - 1) // ROW) if n else 0.0,
            theta=0.0,
            hypotheses=[],
            map_seq=m.seq,
            map_nodes=n,
            map_edges=len(m.edges),
            unexplored=2 * n,
            error=None,
            event_seq=self.event_seq,
        )

    def run(self) -> None:
        a = self.args
        now = time.monotonic()
        next_state = next_scan = next_grow = next_burst = now
        tick = 0.002 if a.burst else 0.01
        while not self.stop.is_set():
            now = time.monotonic()
            if now >= next_grow and a.rate > 0:
                next_grow = now + 1.0 / a.rate
                with self.map.lock:
                    change = None
                    if not self.paused and len(self.map.nodes) < a.nodes:
                        change = self.map.grow()
                        self.link.publish_map_change(change)
                if change is not None:
                    self.event("node", f"new node {change.upsert_nodes[0].id}")
            if self.burst_left > 0 and now >= next_burst:
                next_burst = max(next_burst + 1.0 / a.burst_hz, now - 0.1)
                self.burst_left -= 1
                self.event("bench", f"burst {self.burst_left}")
            if now >= next_state and a.state_hz > 0:
                next_state = now + 1.0 / a.state_hz
                with self.map.lock:
                    s = self.state()
                self.link.publish_state(s)
            if now >= next_scan and a.scan_hz > 0:
                next_scan = now + 1.0 / a.scan_hz
                ranges = [None if k % 5 == 0 else 1.0 + 0.5 * math.sin(now + k) for k in range(16)]
                self.link.publish_scan(ScanMsg(a.robot, now, ranges))
            self.stop.wait(tick)


def parse_args(argv: list[str] | None) -> argparse.Namespace:
    p = argparse.ArgumentParser(prog="python -m tslam.link.demo_robot", description=__doc__)
    p.add_argument("--robot", default="demo")
    p.add_argument("--epoch", default=None, help="default: a fresh random one")
    p.add_argument("--mode", default="peer", choices=("peer", "client"))
    p.add_argument("--listen", action="append", default=[])
    p.add_argument("--connect", action="append", default=[])
    p.add_argument("--zenoh-config", default=None, help="zenoh json5 file to start from")
    p.add_argument("--dictionary-file", default=None, help="accepted user:password lines")
    p.add_argument("--credentials", default=None, help="this robot's user:password file")
    p.add_argument("--lease", type=float, default=1.0, help="link lease, seconds (1)")
    p.add_argument("--nodes", type=int, default=100, help="size the map grows to (100)")
    p.add_argument("--initial", type=int, default=10, help="nodes at start (10)")
    p.add_argument("--rate", type=float, default=10.0, help="nodes added per second (10)")
    p.add_argument("--state-hz", type=float, default=10.0)
    p.add_argument("--scan-hz", type=float, default=5.0)
    p.add_argument("--wait-explore", action="store_true", help="grow only after 'explore'")
    p.add_argument("--burst", type=int, default=0, help="events sent after each 'explore'")
    p.add_argument("--burst-hz", type=float, default=500.0)
    args = p.parse_args(argv)
    if args.epoch is None:
        args.epoch = uuid.uuid4().hex[:12]
    return args


def main(argv: list[str] | None = None) -> int:
    args = parse_args(argv)
    try:
        cfg = LinkConfig(
            mode=args.mode,
            listen=args.listen,
            connect=args.connect,
            config_file=args.zenoh_config,
            dictionary_file=args.dictionary_file,
            lease_s=args.lease,
            open_timeout_s=1.0,
        )
        if args.credentials:
            cfg = cfg.with_credentials_file(args.credentials)
        robot = DemoRobot(args, cfg)
    except LinkError as e:
        print(f"demo_robot: {e}", file=sys.stderr)
        return 2
    print(f"ready {args.epoch}", flush=True)
    try:
        with stop_on_signals(robot.stop.set):
            robot.run()
    finally:
        robot.link.close()
        robot.stop.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())

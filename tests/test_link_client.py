"""RobotLink and MonitorClient in one process (two zenoh sessions on loopback): the monitor's
bookkeeping of gaps, epochs and commands, driven by a robot the test controls exactly."""

from __future__ import annotations

import threading
import time

import pytest

from tests.link_rig import wait_until
from tslam.link import LinkError
from tslam.link.client import MonitorClient
from tslam.link.config import free_port, loopback
from tslam.link.robot import RobotLink
from tslam.link.schemas import (
    Command,
    CommandReply,
    EdgeMsg,
    EventMsg,
    MapChange,
    MapSnapshot,
    NodeMsg,
    encode,
)


def node(i: int) -> NodeMsg:
    return NodeMsg(id=i, kind="meet", x=float(i), y=0.0, clearance_m=1.0, degree=3, unexplored=2)


class FakeRobot:
    """A map the test edits by hand; ``publish`` can skip sending a change (a lost sample)."""

    def __init__(self, port: int, epoch: str = "e1", on_command=None) -> None:
        self.lock = threading.Lock()
        self.nodes: dict[int, NodeMsg] = {}
        self.edges: dict[int, EdgeMsg] = {}
        self.seq = 0
        self.epoch = epoch
        self.snapshot_error: Exception | None = None
        self.link = RobotLink(
            "r1",
            loopback(port, []),
            epoch,
            snapshot=self.snapshot,
            on_command=on_command or (lambda c: CommandReply(c.id, True, "ok")),
        )

    def snapshot(self) -> MapSnapshot:
        if self.snapshot_error is not None:
            raise self.snapshot_error
        with self.lock:
            return MapSnapshot(
                "r1", self.epoch, self.seq, list(self.nodes.values()), list(self.edges.values())
            )

    def add(self, i: int, send: bool = True) -> None:
        with self.lock:
            self.nodes[i] = node(i)
            self.seq += 1
            edges = []
            if i > 0:
                e = EdgeMsg(id=len(self.edges), u=i - 1, v=i, length_m=1.0)
                self.edges[e.id] = e
                edges.append(e)
            if send:
                self.link.publish_map_change(
                    MapChange("r1", self.epoch, self.seq, "node_added", [node(i)], [], edges, [])
                )


@pytest.fixture
def port():
    return free_port()


def in_step(mon: MonitorClient, robot: FakeRobot):
    v = mon.view()
    return v.synced and v.seq == robot.seq and v.nodes == robot.nodes and v.edges == robot.edges


def test_a_missing_seq_is_a_gap_repaired_by_a_snapshot(port):
    robot = FakeRobot(port)
    try:
        for i in range(3):
            robot.add(i)
        with MonitorClient("r1", loopback(None, [port])) as mon:
            assert wait_until(lambda: in_step(mon, robot))
            assert mon.view().snapshots == 1 and mon.view().gaps == 0
            robot.add(3, send=False)  # lost on the way
            robot.add(4)
            assert wait_until(lambda: in_step(mon, robot) and mon.view().gaps == 1), mon.view()
            assert mon.view().snapshots == 2
            robot.add(5)
            assert wait_until(lambda: in_step(mon, robot))
            assert mon.view().gaps == 1
    finally:
        robot.link.close()


def test_changes_and_events_are_applied_once_in_order(port):
    robot = FakeRobot(port)
    got: list[int] = []
    try:
        with MonitorClient(
            "r1", loopback(None, [port]), on_event=lambda e: got.append(e.seq)
        ) as mon:
            assert wait_until(lambda: mon.view().synced)
            for i in range(50):
                robot.add(i)
                robot.link.publish_event(EventMsg("r1", "e1", i + 1, 0.0, "node", f"node {i}"))
            assert wait_until(lambda: in_step(mon, robot) and len(got) == 50), mon.view()
            assert got == list(range(1, 51))
            assert [e.seq for e in mon.view().events] == list(range(1, 51))
    finally:
        robot.link.close()


def test_a_snapshot_failure_is_reported_and_retried(port):
    robot = FakeRobot(port)
    robot.snapshot_error = RuntimeError("disk on fire")
    try:
        robot.add(0)
        with MonitorClient("r1", loopback(None, [port])) as mon:
            assert wait_until(lambda: "disk on fire" in (mon.view().last_error or ""))
            assert not mon.view().synced
            robot.snapshot_error = None
            assert wait_until(lambda: in_step(mon, robot))
            assert mon.view().last_error is None
    finally:
        robot.link.close()


def test_on_command_errors_and_bad_replies_become_refusals(port):
    def on_command(c: Command):
        if c.op == "stop":
            raise RuntimeError("motor controller gone")
        if c.op == "explore":
            return "yes"
        return CommandReply(c.id, True, "fine")

    robot = FakeRobot(port, on_command=on_command)
    try:
        with MonitorClient("r1", loopback(None, [port])) as mon:
            assert wait_until(lambda: mon.view().online)
            r = mon.command(Command(id="s", op="stop"))
            assert (r.id, r.accepted) == ("s", False) and "motor controller gone" in r.reason
            r = mon.command(Command(id="x", op="explore"))
            assert not r.accepted and "returned str" in r.reason
            r = mon.command(Command(id="p", op="pause"))
            assert r == CommandReply("p", True, "fine")
            r = mon.command_bytes(b"")
            assert not r.accepted and "empty" in r.reason
            r = mon.command_bytes(encode(EventMsg("r1", "e", 1, 0.0, "k", "t")))
            assert not r.accepted and r.reason.startswith("malformed command")
    finally:
        robot.link.close()


def test_no_robot_means_a_refusal_within_the_timeout(port):
    with MonitorClient("r1", loopback(None, [port])) as mon:
        t0 = time.monotonic()
        r = mon.command(Command(id="a", op="pause"), timeout_s=1.0)
        assert not r.accepted and "no reply" in r.reason
        assert time.monotonic() - t0 < 10
        with pytest.raises(LinkError, match="no map"):
            mon.fetch_snapshot(timeout_s=0.5)
        assert not mon.view().online and mon.view().state is None


def test_close_is_idempotent_and_publishing_after_close_is_harmless(port):
    robot = FakeRobot(port)
    mon = MonitorClient("r1", loopback(None, [port]))
    assert wait_until(lambda: mon.view().online)
    t0 = time.monotonic()
    robot.link.close()
    robot.link.close()
    robot.add(0)  # publishes into a closed link: ignored
    assert wait_until(lambda: not mon.view().online)
    mon.close()
    mon.close()
    assert time.monotonic() - t0 < 15
    r = mon.command(Command(id="a", op="pause"))
    assert not r.accepted and "closed" in r.reason


def test_bad_names_are_refused_before_anything_opens(port):
    with pytest.raises(LinkError, match="robot name"):
        MonitorClient("r/1", loopback(None, [port]))
    with pytest.raises(LinkError, match="robot name"):
        RobotLink("", loopback(port, []), "e", snapshot=lambda: None, on_command=lambda c: None)
    with pytest.raises(LinkError, match="epoch"):
        RobotLink("r", loopback(port, []), "", snapshot=lambda: None, on_command=lambda c: None)

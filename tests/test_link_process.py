"""The link across processes on loopback: a robot process (``tslam.link.demo_robot``) serving a
synthetic map, followed by monitors in this process. Only 127.0.0.1, explicit free ports, no
multicast; every wait is a poll with a generous deadline, never a fixed sleep that has to be
long enough; every child process is reaped even when a test fails."""

from __future__ import annotations

import signal

import pytest

from tests.link_rig import Children, Relay, wait_until
from tslam.link.client import MonitorClient
from tslam.link.config import LinkConfig, free_port, loopback
from tslam.link.demo_robot import SyntheticMap
from tslam.link.schemas import Command, encode


@pytest.fixture
def children():
    kids = Children()
    try:
        yield kids
    finally:
        kids.close()


def robot_args(port: int, robot: str = "r1", **opts: object) -> list[str]:
    args = ["--robot", robot, "--listen", f"tcp/127.0.0.1:{port}"]
    for k, v in opts.items():
        args += [f"--{k.replace('_', '-')}", str(v)]
    return args


def expected_map(n: int) -> SyntheticMap:
    m = SyntheticMap("r1", "x")
    for _ in range(n):
        m.grow()
    return m


def has_map(client: MonitorClient, n: int):
    """The view, once it holds exactly the robot's n-node map and the state says n too."""
    v = client.view()
    ok = (
        v.online
        and v.synced
        and len(v.nodes) == n
        and v.state is not None
        and v.state.map_nodes == n
        and v.seq == v.state.map_seq
    )
    return v if ok else None


def same_map(v, n: int) -> None:
    want = expected_map(n)
    assert v.nodes == want.nodes
    assert v.edges == want.edges


def test_a_late_monitor_gets_the_whole_map_state_and_events(children):
    port = free_port()
    robot = children.robot(*robot_args(port, initial=40, nodes=120, rate=200))
    epoch = robot.ready_line.split()[1]  # "ready <epoch>"
    with MonitorClient("r1", loopback(None, [port])) as first:
        # Wait until the map has stopped growing, then join late: nothing is live any more
        # but the state, so the map must come from the snapshot and the events from history.
        assert wait_until(lambda: has_map(first, 120))
    with MonitorClient("r1", loopback(None, [port])) as late:
        v = wait_until(lambda: has_map(late, 120) and late.view().events)
        assert v, late.view()
        v = late.view()
        same_map(v, 120)
        assert v.state.robot == "r1" and v.state.mode == "exploring"
        assert v.epoch == v.state.epoch == epoch
        kinds = {e.kind for e in v.events}
        assert "node" in kinds and len(v.events) <= 50
        assert v.gaps == 0 and v.malformed == 0
        assert late.robots() == ["r1"]


def test_a_monitor_joining_mid_exploration_follows_every_change(children):
    port = free_port()
    children.robot(*robot_args(port, initial=5, nodes=300, rate=100))
    with MonitorClient("r1", loopback(None, [port])) as mon:
        v = wait_until(lambda: has_map(mon, 300))
        assert v, mon.view()
        same_map(v, 300)


def test_a_frozen_robot_goes_offline_and_is_followed_again(children):
    port = free_port()
    robot = children.robot(*robot_args(port, initial=10, nodes=100_000, rate=20))
    with MonitorClient("r1", loopback(None, [port])) as mon:
        assert wait_until(lambda: mon.view().synced and mon.view().seq > 12)
        robot.signal(signal.SIGSTOP)
        assert wait_until(lambda: not mon.view().online), "a frozen robot must go offline"
        robot.signal(signal.SIGCONT)
        before = mon.view().seq

        def recovered():
            v = mon.view()
            return v.online and v.synced and v.seq > before + 5 and v.gaps >= 1

        assert wait_until(recovered), mon.view()
        v = mon.view()
        same_map(v, len(v.nodes))  # whole and in order, no hole


def test_a_cut_link_is_detected_and_the_gap_repaired(children):
    port = free_port()
    children.robot(*robot_args(port, initial=10, nodes=100_000, rate=20))
    relay = Relay(port)
    try:
        with MonitorClient("r1", loopback(None, [relay.port])) as mon:
            assert wait_until(lambda: mon.view().synced and mon.view().seq > 12)
            relay.cut()
            assert wait_until(lambda: not mon.view().online)
            held = mon.view().seq
            relay.restore()

            def repaired():
                v = mon.view()
                return v.online and v.synced and v.gaps >= 1 and v.seq > held

            assert wait_until(repaired), mon.view()
            v = mon.view()
            same_map(v, len(v.nodes))
            assert v.snapshots >= 2
    finally:
        relay.close()


def test_a_restarted_robot_is_followed_into_its_new_epoch(children):
    port = free_port()
    first = children.robot(*robot_args(port, initial=30, rate=0, epoch="one"))
    with MonitorClient("r1", loopback(None, [port])) as mon:
        assert wait_until(lambda: has_map(mon, 30))
        assert mon.view().epoch == "one"
        first.signal(signal.SIGKILL)
        assert wait_until(lambda: not mon.view().online)
        children.robot(*robot_args(port, initial=7, rate=0, epoch="two"))

        def followed():
            v = has_map(mon, 7)
            return v if v and v.epoch == "two" and v.state.epoch == "two" else None

        v = wait_until(followed)
        assert v, mon.view()
        same_map(v, 7)
        assert v.gaps == 0  # a restart is a new map, not a repaired gap


def test_commands_are_acknowledged_or_refused_with_a_reason(children):
    port = free_port()
    children.robot(*robot_args(port, initial=5, nodes=50, rate=0))
    with MonitorClient("r1", loopback(None, [port])) as mon:
        assert wait_until(lambda: has_map(mon, 5))
        bad = mon.command_bytes(b"\xc1 not msgpack")
        assert not bad.accepted and bad.reason.startswith("malformed command")
        bad = mon.command_bytes(encode(Command(id="a", op="pause")).replace(b"op", b"oq"))
        assert not bad.accepted and "malformed command" in bad.reason and "op" in bad.reason
        r = mon.command(Command(id="b", op="fly"))
        assert (r.id, r.accepted) == ("b", False) and "unknown op 'fly'" in r.reason
        r = mon.command(Command(id="c", op="goto"))
        assert not r.accepted and "goto needs a node" in r.reason
        r = mon.command(Command(id="d", op="goto", node=999))
        assert not r.accepted and "no node 999" in r.reason
        assert not mon.view().state.paused
        r = mon.command(Command(id="e", op="pause"))
        assert (r.id, r.accepted) == ("e", True)
        assert wait_until(lambda: mon.view().state.paused)
        r = mon.command(Command(id="f", op="goto", node=3))
        assert r.accepted
        assert wait_until(lambda: mon.view().state.goal_node == 3)


def test_several_monitors_see_the_same_robot(children):
    port = free_port()
    children.robot(*robot_args(port, initial=20, nodes=150, rate=100))
    mons = [MonitorClient("r1", loopback(None, [port])) for _ in range(3)]
    try:
        for m in mons:
            assert wait_until(lambda m=m: has_map(m, 150)), m.view()
        r = mons[0].command(Command(id="p", op="pause"))
        assert r.accepted
        for m in mons:
            assert wait_until(lambda m=m: m.view().state.paused)
        views = [m.view() for m in mons]
        assert all(v.nodes == views[0].nodes and v.edges == views[0].edges for v in views)
    finally:
        for m in mons:
            m.close()


def test_a_monitor_started_before_its_robot_finds_it(children):
    port = free_port()
    with MonitorClient("r1", loopback(None, [port])) as mon:
        assert not mon.view().online and mon.robots() == []
        children.robot(*robot_args(port, initial=12, rate=0))
        assert wait_until(lambda: has_map(mon, 12)), mon.view()


def test_robots_lists_each_robot_alive_and_drops_a_stopped_one(children):
    p1, p2 = free_port(), free_port()
    a = children.robot(*robot_args(p1, robot="alpha", rate=0))
    children.robot(*robot_args(p2, robot="beta", rate=0))
    cfg = LinkConfig(mode="peer", connect=[f"tcp/127.0.0.1:{p1}", f"tcp/127.0.0.1:{p2}"])
    with MonitorClient("alpha", cfg) as mon:
        assert wait_until(lambda: mon.robots() == ["alpha", "beta"]), mon.robots()
        a.stop()
        assert wait_until(lambda: mon.robots() == ["beta"]), mon.robots()
        assert not mon.view().online

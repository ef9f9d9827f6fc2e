"""Authentication and access control with the shipped zenoh configurations (deploy/zenoh/):
a viewer credential can follow a robot but not command it, an operator can, an unknown or
wrong credential gets nothing; on the robot's own peer session and through a fleet router
(``python -m tslam.link.router``). Loopback only; the files' endpoints and paths are replaced
by free ports and temporary files, their access control rules are used as shipped."""

from __future__ import annotations

import pytest

from tests.link_rig import DEPLOY, Children, wait_until
from tslam.link.client import MonitorClient
from tslam.link.config import LinkConfig, free_port
from tslam.link.schemas import Command

USERS = {"alice": "alice-pw", "bob": "bob-pw", "robot1": "robot1-pw", "robot2": "robot2-pw"}


@pytest.fixture
def children():
    kids = Children()
    try:
        yield kids
    finally:
        kids.close()


@pytest.fixture
def users(tmp_path):
    path = tmp_path / "users.txt"
    path.write_text("".join(f"{u}:{p}\n" for u, p in USERS.items()))
    path.chmod(0o600)
    return path


def creds(tmp_path, user: str, password: str | None = None):
    path = tmp_path / f"{user}.cred"
    path.write_text(f"{user}:{password or USERS[user]}\n")
    return str(path)


def monitor(robot: str, port: int, user: str, password: str | None = None, mode="peer"):
    cfg = LinkConfig(
        mode=mode,
        connect=[f"tcp/127.0.0.1:{port}"],
        user=user,
        password=password or USERS[user],
        lease_s=1.0,
        open_timeout_s=1.0,
    )
    return MonitorClient(robot, cfg)


def follows(mon: MonitorClient, n: int):
    v = mon.view()
    return v.online and v.synced and len(v.nodes) == n and v.state is not None and v.events


def check_viewer_and_operator(robot: str, port: int, mode: str) -> None:
    with (
        monitor(robot, port, "bob", mode=mode) as viewer,
        monitor(robot, port, "alice", mode=mode) as op,
    ):
        # Both may follow: map, state and history.
        assert wait_until(lambda: follows(viewer, 8)), viewer.view()
        assert wait_until(lambda: follows(op, 8)), op.view()
        # The viewer's command is dropped by access control: a refusal, quickly, no exception.
        r = viewer.command(Command(id="v1", op="pause"), timeout_s=3.0)
        assert not r.accepted and "not authorised" in r.reason
        r = viewer.command(Command(id="v2", op="goto", node=2), timeout_s=3.0)
        assert not r.accepted
        # The operator's goto goes through; had the viewer's pause reached the robot, which
        # handles commands in order, the state would now say paused.
        r = op.command(Command(id="o1", op="goto", node=5))
        assert r.accepted, r
        assert wait_until(lambda: viewer.view().state.goal_node == 5)
        assert not viewer.view().state.paused
        r = op.command(Command(id="o2", op="pause"))
        assert r.accepted
        assert wait_until(lambda: viewer.view().state.paused)


def test_on_the_robots_own_session_a_viewer_cannot_command(children, users, tmp_path):
    port = free_port()
    children.robot(
        "--robot", "robot1", "--initial", "8", "--rate", "0",
        "--zenoh-config", str(DEPLOY / "robot-peer.json5"),
        "--listen", f"tcp/127.0.0.1:{port}",
        "--dictionary-file", str(users),
        "--credentials", creds(tmp_path, "robot1"),
    )  # fmt: skip
    check_viewer_and_operator("robot1", port, mode="peer")
    # A laptop in client mode, as deploy/zenoh/laptop-client.json5 has it, is treated alike.
    with monitor("robot1", port, "bob", mode="client") as viewer:
        assert wait_until(lambda: follows(viewer, 8))
        assert not viewer.command(Command(id="v3", op="stop"), timeout_s=3.0).accepted
    # In the users file but in no subject of the rules: sees nothing (default deny).
    with monitor("robot1", port, "robot2") as stranger:
        r = stranger.command(Command(id="s1", op="stop"), timeout_s=2.0)
        assert not r.accepted
        assert not stranger.view().synced and stranger.view().nodes == {}
    # A wrong password is refused at the door.
    with monitor("robot1", port, "alice", password="guess") as intruder:
        r = intruder.command(Command(id="i1", op="stop"), timeout_s=2.0)
        assert not r.accepted and not intruder.view().online


def test_through_a_fleet_router_a_viewer_cannot_command(children, users, tmp_path):
    port = free_port()
    children.start(
        "tslam.link.router",
        "--config", str(DEPLOY / "fleet-router.json5"),
        "--listen", f"tcp/127.0.0.1:{port}",
        "--dictionary-file", str(users),
        "--lease", "1",
    )  # fmt: skip
    children.robot(
        "--robot", "robot1", "--initial", "8", "--rate", "0", "--mode", "client",
        "--connect", f"tcp/127.0.0.1:{port}",
        "--credentials", creds(tmp_path, "robot1"),
    )  # fmt: skip
    check_viewer_and_operator("robot1", port, mode="client")
    # robot1's credential cannot serve as robot2: the router drops it.
    children.robot(
        "--robot", "robot2", "--initial", "3", "--rate", "0", "--mode", "client",
        "--connect", f"tcp/127.0.0.1:{port}",
        "--credentials", creds(tmp_path, "robot1"),
    )  # fmt: skip
    with monitor("robot2", port, "alice", mode="client") as op:
        assert wait_until(lambda: op.robots() == ["robot1"])
        r = op.command(Command(id="x", op="pause"), timeout_s=2.0)
        assert not r.accepted and not op.view().online


def test_the_router_refuses_a_bad_config_in_one_line(children, tmp_path):
    bad = tmp_path / "bad.json5"
    bad.write_text("{ mode: ")
    child = children.start("tslam.link.router", "--config", str(bad), ready=None)
    assert child.proc.wait(30) == 2
    wait_until(lambda: child.stderr)
    assert len(child.stderr) == 1 and child.stderr[0].startswith("router: zenoh config")

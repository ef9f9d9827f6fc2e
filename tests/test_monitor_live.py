"""``tslam monitor`` across processes against a fake robot on loopback: --json --once, commands,
the live terminal view, and the errors a user meets (unknown robot, bad endpoint)."""

from __future__ import annotations

import json
import signal
import socket
import sys
import time

import pytest

from tests.monitor_procs import Proc, monitor_argv, run_monitor, start_robot
from tslam.link.config import free_port


@pytest.fixture
def robot():
    proc, port = start_robot("r1", nodes=4)
    try:
        yield proc, f"tcp/127.0.0.1:{port}"
    finally:
        proc.close()


def snapshot(endpoint: str, *extra: str) -> dict:
    res = run_monitor("--connect", endpoint, "--json", "--once", "--timeout", "10", *extra)
    assert res.returncode == 0, res.stderr
    return json.loads(res.stdout)


def test_json_once_gives_state_map_and_events(robot):
    _, endpoint = robot
    snap = snapshot(endpoint, "--robot", "r1")
    assert snap["robot"] == "r1" and snap["online"] is True
    assert snap["state"]["behaviour"] == "trace_edge" and snap["state"]["current_node"] == 3
    assert len(snap["map"]["nodes"]) == 4 and len(snap["map"]["edges"]) == 3
    assert snap["map"]["nodes"][0]["ambiguous_with"] == [1]
    assert any(e["text"] == "fake robot up" for e in snap["events"])


def test_json_once_follows_the_only_robot_and_sees_later_changes(robot):
    proc, endpoint = robot
    proc.send("add")
    proc.expect("^ok$")
    snap = snapshot(endpoint)  # no --robot: the only one online
    assert snap["robot"] == "r1"
    assert len(snap["map"]["nodes"]) == 5 and snap["state"]["map_nodes"] == 5


def test_several_robots_without_robot_is_a_user_error():
    # The second robot connects to the first, so one endpoint shows both.
    first, port = start_robot("alpha", nodes=2)
    second = Proc(
        [sys.executable, "-m", "tests.monitor_fake_robot", "--robot", "beta",
         "--listen", str(free_port()), "--nodes", "2", "--connect", str(port)],
        stdin=True,
    )  # fmt: skip
    try:
        second.expect("^ready$", 20.0)
        res = run_monitor("--connect", f"tcp/127.0.0.1:{port}", "--once", "--timeout", "10")
        assert res.returncode == 2
        assert "several robots online (alpha, beta)" in res.stderr
        assert len(res.stderr.strip().splitlines()) == 1
    finally:
        second.close()
        first.close()


def test_commands_are_acknowledged_or_refused(robot):
    _, endpoint = robot
    res = run_monitor("--connect", endpoint, "--robot", "r1", "--command", "pause")
    assert res.returncode == 0 and "r1: pause: accepted" in res.stdout, res.stderr
    res = run_monitor("--connect", endpoint, "--robot", "r1", "--command", "goto", "--node", "99")
    assert res.returncode == 1
    assert "goto 99: refused: no node 99 in the map" in res.stdout
    res = run_monitor(
        "--connect", endpoint, "--robot", "r1", "--command", "goto", "--node", "2", "--json"
    )
    assert res.returncode == 0 and json.loads(res.stdout)["accepted"] is True
    state = snapshot(endpoint, "--robot", "r1")["state"]
    assert state["paused"] is True and state["goal_node"] == 2 and state["mode"] == "goto"


def test_unknown_robot_exits_1_within_the_timeout(robot):
    _, endpoint = robot
    for extra in (["--json", "--once"], ["--command", "stop"]):
        res = run_monitor("--connect", endpoint, "--robot", "nobody", "--timeout", "1", *extra)
        assert res.returncode == 1
        assert "robot 'nobody' not seen" in res.stderr
        assert len(res.stderr.strip().splitlines()) == 1 and "Traceback" not in res.stderr


def test_unreachable_endpoint_is_a_one_line_error():
    res = run_monitor("--connect", f"tcp/127.0.0.1:{free_port()}", "--once", "--timeout", "1")
    assert res.returncode == 2 and "Unable to connect" in res.stderr
    assert len(res.stderr.strip().splitlines()) == 1 and "Traceback" not in res.stderr


@pytest.mark.parametrize(
    "args, message",
    [
        (["--connect", "nonsense"], "is not an endpoint"),
        (["--connect", "tcp/127.0.0.1:99999"], "port must be"),
        (["--connect", "tcp/127.0.0.1:7447", "--command", "goto"], "needs --node"),
        (["--connect", "tcp/127.0.0.1:7447", "--node", "3"], "--command goto only"),
        (["--connect", "tcp/127.0.0.1:7447", "--user", "u"], "go together"),
        (["--connect", "tcp/127.0.0.1:7447", "--config", "/no/such.json5"], "no such file"),
        (["--connect", "tcp/127.0.0.1:7447", "--web", "0", "--once"], "cannot be combined"),
        (["--connect", "tcp/127.0.0.1:7447", "--robot", "a/b"], "not valid"),
        (["--robot", "r1"], "--connect ENDPOINT is needed"),
        (["--connect", "tcp/127.0.0.1:7447", "--credentials", "/no/such"], "credentials file"),
    ],
)
def test_bad_options_are_one_line_errors(args, message):
    res = run_monitor(*args, "--timeout", "1")
    assert res.returncode == 2, res.stderr
    assert message in res.stderr and len(res.stderr.strip().splitlines()) == 1
    assert "Traceback" not in res.stderr


def test_live_view_follows_changes_and_exits_on_ctrl_c(robot):
    proc, endpoint = robot
    mon = Proc(monitor_argv("--connect", endpoint, "--robot", "r1"))
    try:
        mon.expect("behaviour trace_edge", 20.0)
        mon.expect(r"map: 4 nodes, 3 edges", 20.0)
        proc.send("behaviour homing")
        mon.expect("behaviour homing")
        proc.send("add")
        mon.expect(r"map: 5 nodes, 4 edges")
        mon.expect("new node 4")
        assert mon.interrupt() == 0
    finally:
        mon.close()


def test_live_view_shows_the_robot_going_offline_and_exits_on_sigterm(robot):
    proc, endpoint = robot
    mon = Proc(monitor_argv("--connect", endpoint, "--robot", "r1", "--json"))
    try:
        first = json.loads(mon.expect(r"^\{.*\"online\":true").string)
        assert first["robot"] == "r1"
        proc.send("quit")
        mon.expect(r"^\{.*\"online\":false")
        mon.proc.send_signal(signal.SIGTERM)
        assert mon.proc.wait(timeout=10) == 0
    finally:
        mon.close()


def demo_robot(port: int, *extra: str) -> Proc:
    """The link's own synthetic robot (``tslam.link.demo_robot``), ready."""
    demo = Proc(
        [sys.executable, "-m", "tslam.link.demo_robot", "--robot", "demo",
         "--listen", f"tcp/127.0.0.1:{port}", *extra]
    )  # fmt: skip
    try:
        demo.expect("^ready", 20.0)
    except BaseException:
        demo.close()
        raise
    return demo


def test_live_json_keeps_up_with_a_growing_map():
    port = free_port()
    demo = demo_robot(port, "--nodes", "60", "--initial", "5", "--rate", "30")
    mon = Proc(monitor_argv("--connect", f"tcp/127.0.0.1:{port}", "--json"))
    try:
        deadline = time.monotonic() + 30
        while True:
            assert time.monotonic() < deadline, "the map never reached 60 nodes"
            snap = json.loads(mon.expect(r"^\{").string)
            # The state and the map travel apart: wait for both to say 60.
            state = snap["state"] or {}
            if len(snap["map"]["nodes"]) == 60 and snap["synced"] and (
                state.get("map_nodes") == 60
            ):
                break
        assert snap["robot"] == "demo"
        ids = [n["id"] for n in snap["map"]["nodes"]]
        assert ids == list(range(60))
        assert all(e["u"] in ids and e["v"] in ids for e in snap["map"]["edges"])
        assert mon.interrupt() == 0
    finally:
        mon.close()
        demo.close()


def test_credentials_reach_the_robot(tmp_path):
    users = tmp_path / "users.txt"
    users.write_text("operator:s3cret\n")
    port = free_port()
    demo = demo_robot(port, "--dictionary-file", str(users), "--nodes", "3", "--initial", "3")
    endpoint = f"tcp/127.0.0.1:{port}"
    try:
        res = run_monitor(
            "--connect", endpoint, "--user", "operator", "--password", "s3cret",
            "--json", "--once", "--timeout", "10",
        )  # fmt: skip
        assert res.returncode == 0, res.stderr
        assert len(json.loads(res.stdout)["map"]["nodes"]) == 3
        # A credentials file, and a zenoh config file naming the endpoint instead of --connect.
        creds = tmp_path / "credentials"
        creds.write_text("# mine\noperator:s3cret\n")
        conf = tmp_path / "laptop.json5"
        conf.write_text(f'{{ mode: "client", connect: {{ endpoints: ["{endpoint}"] }} }}\n')
        res = run_monitor(
            "--config", str(conf), "--credentials", str(creds), "--once", "--timeout", "10"
        )
        assert res.returncode == 0 and "robot demo: ONLINE" in res.stdout, res.stderr
        res = run_monitor(
            "--connect", endpoint, "--user", "operator", "--password", "guess", "--once"
        )
        assert res.returncode == 2 and "credentials" in res.stderr
        # zenoh's own log lines stay out of the user's way: one line, ours.
        assert len(res.stderr.strip().splitlines()) == 1
    finally:
        demo.close()


def test_web_port_in_use_is_a_one_line_error(robot):
    _, endpoint = robot
    with socket.socket() as busy:
        busy.bind(("127.0.0.1", 0))
        busy.listen()
        port = busy.getsockname()[1]
        res = run_monitor("--connect", endpoint, "--robot", "r1", "--web", str(port))
    assert res.returncode == 2 and f"cannot serve on 127.0.0.1:{port}" in res.stderr
    assert len(res.stderr.strip().splitlines()) == 1

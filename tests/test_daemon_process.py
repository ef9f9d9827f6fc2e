"""``tslam daemon`` as a process, on loopback: it explores, publishes, obeys commands, keeps
its map through SIGKILL, stops cleanly on SIGTERM and talks to systemd."""

from __future__ import annotations

import json
import os
import signal
import socket
import time

import pytest

from tests.link_rig import Children, wait_until
from tslam.link.client import MonitorClient
from tslam.link.config import free_port, loopback
from tslam.link.schemas import Command
from tslam.programs.map_files import load_map


def config(tmp_path, port: int, time_scale: float, name: str = "robot.toml") -> str:
    path = tmp_path / name
    path.write_text(
        f"""
robot = "sim-t"
storage = "{tmp_path / 'store'}"
rate_hz = 10.0
watchdog_s = 5.0

[backend]
backend = "sim"
world = "fig12"
seed = 1

[sim]
time_scale = {time_scale}

[link]
listen = ["tcp/127.0.0.1:{port}"]
"""
    )
    return str(path)


@pytest.fixture
def children():
    kids = Children()
    yield kids
    kids.close()


def daemon(children: Children, cfg: str, *extra: str):
    return children.start("tslam.programs.cli", "daemon", "--config", cfg, *extra, ready=None)


def stored_map(tmp_path):
    path = tmp_path / "store" / "map.json"
    return load_map(path) if path.exists() else None


def test_sigkill_mid_exploration_then_restart_keeps_the_map(tmp_path, children):
    port = free_port()
    first = daemon(children, config(tmp_path, port, 40.0))
    # Killed once the map holds a node and its first edge: the map on disk is whole.
    held = wait_until(lambda: (m := stored_map(tmp_path)) and len(m.edges()) >= 1 and m, 120)
    assert held, f"no map written; stderr: {first.stderr[-5:]}"
    first.signal(signal.SIGKILL)
    first.proc.wait(10)
    killed = stored_map(tmp_path)  # parses: never half written
    assert killed is not None and len(killed.nodes()) >= 2
    before = {n.id: n for n in killed.nodes()}

    second = daemon(children, config(tmp_path, port, 0.0, "fast.toml"), "--exit-when-done")
    assert second.proc.wait(300) == 0, second.stderr[-10:]
    loaded = [line for line in second.stderr if line.startswith("map loaded from")]
    assert loaded and f"{len(before)} nodes" in loaded[0]
    final = stored_map(tmp_path)
    assert not final.unexplored()
    # What it knew before the kill is still there under the same names (merges keep the old
    # node), with every edge it had measured.
    assert set(before) <= {n.id for n in final.nodes()}
    assert {e.id for e in killed.edges()} <= {e.id for e in final.edges()}


def test_monitor_joining_late_gets_the_map_and_commands_are_answered(tmp_path, children):
    port = free_port()
    d = daemon(children, config(tmp_path, port, 20.0))
    assert wait_until(lambda: (m := stored_map(tmp_path)) and len(m.nodes()) >= 2, 120)
    with MonitorClient("sim-t", loopback(None, [port])) as mon:
        view = wait_until(lambda: (v := mon.view()).synced and v.state and v, 30)
        assert view, "monitor never synced"
        assert view.online and len(view.nodes) >= 2
        assert mon.command(Command("a", "goto", 999)).reason == "there is no node 999 in the map"
        assert mon.command(Command("b", "fly")).accepted is False
        assert mon.command(Command("c", "pause")).accepted
        assert wait_until(lambda: mon.view().state.paused, 10)
        # Paused, the map holds still: the monitor's copy is the one on disk, node for node.
        on_disk = {n.id for n in stored_map(tmp_path).nodes()}
        assert wait_until(lambda: set(mon.view().nodes) == on_disk, 10), (on_disk, mon.view())
        time.sleep(1.0)  # braking takes the drive's deceleration (0.7 s simulated at most)
        paused_at = mon.view().state
        time.sleep(1.0)  # paused: the robot stands (dead reckoning does not move)
        now = mon.view().state
        assert now.stamp_s > paused_at.stamp_s  # time goes on, the loop runs
        assert abs(now.x - paused_at.x) < 1e-6 and abs(now.y - paused_at.y) < 1e-6
        assert mon.command(Command("d", "resume")).accepted
        assert wait_until(lambda: not mon.view().state.paused, 10)
        orders = json.loads((tmp_path / "store" / "daemon_state.json").read_text())
        assert orders["halted"] is None
    d.signal(signal.SIGTERM)
    assert d.exit_code(30) == 0


def test_sigterm_stops_saves_and_tells_systemd(tmp_path, children):
    sock_path = tmp_path / "notify.sock"
    sock = socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM)
    sock.bind(str(sock_path))
    sock.settimeout(60)
    os.environ["NOTIFY_SOCKET"] = str(sock_path)
    try:
        d = daemon(children, config(tmp_path, free_port(), 10.0))
    finally:
        del os.environ["NOTIFY_SOCKET"]
    try:
        got = sock.recv(4096).decode()
        assert "READY=1" in got
        d.signal(signal.SIGTERM)
        assert d.exit_code(30) == 0
        rest = []
        sock.settimeout(1)
        while True:
            try:
                rest.append(sock.recv(4096).decode())
            except TimeoutError:
                break
        assert any("STOPPING=1" in m for m in rest)
    finally:
        sock.close()
    assert any("SIGTERM" in line for line in d.stderr)
    assert (tmp_path / "store" / "map.json").exists()
    assert json.loads((tmp_path / "store" / "daemon_state.json").read_text())["version"] == 1

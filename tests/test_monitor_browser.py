"""The monitor's web page in headless Chromium, against a fake robot, across processes.

A fake robot and ``tslam monitor --web 0`` run as processes on 127.0.0.1; Chromium opens the
page and the test polls its DOM: the map (one circle per node, the current node and the
look-alikes marked), the robot's state, then changes made on the robot's side (a new node,
a new behaviour, a command from the page's buttons, the robot going away) showing up live.

Needs Debian's ``chromium``; missing, the test fails saying so, unless TSLAM_SKIP_BROWSER=1.
"""

from __future__ import annotations

import json
import urllib.error
import urllib.request

import pytest

from tests.chromium_cdp import Browser, chromium_path
from tests.monitor_procs import Proc, monitor_argv, start_robot

NODES = "document.querySelectorAll('#nodes circle.node').length"
EDGES = "document.querySelectorAll('#edges line.edge').length"


def text(id_: str) -> str:
    return f"document.getElementById('{id_}').textContent"


@pytest.fixture
def setup():
    robot, port = start_robot("r1", nodes=4)
    monitor = Proc(monitor_argv("--connect", f"tcp/127.0.0.1:{port}", "--robot", "r1",
                                "--web", "0"))  # fmt: skip
    try:
        url = monitor.expect(r"serving (http://127\.0\.0\.1:\d+/)", 20.0).group(1)
        yield robot, monitor, url
    finally:
        monitor.close()
        robot.close()


def test_page_shows_the_live_map_state_and_commands(setup):
    chromium_path()  # fail (or skip) at once, saying why
    robot, monitor, url = setup
    with Browser() as b:
        b.open(url)
        # The map as the robot has it.
        assert b.wait_for(f"{NODES} === 4 && {EDGES} === 3")
        assert b.wait_for(f"{text('st-behaviour')} === 'trace_edge'")
        assert b.eval(text("st-online")) == "online"
        assert b.eval("document.querySelector('circle.current').dataset.id") == "3"
        ambiguous = b.eval(
            "[...document.querySelectorAll('circle.ambiguous')].map(c => c.dataset.id)"
        )
        assert sorted(ambiguous) == ["0", "1"]
        assert b.eval(text("st-map")).startswith("4 nodes, 3 edges")
        assert "fake robot up" in b.eval(text("events"))

        # Changes on the robot's side reach the open page without a reload.
        robot.send("add")
        assert b.wait_for(f"{NODES} === 5 && {EDGES} === 4")
        assert b.wait_for("document.querySelector('circle.current').dataset.id === '4'")
        robot.send("behaviour homing")
        assert b.wait_for(f"{text('st-behaviour')} === 'homing'")

        # A command from the page's button: sent over the link, acknowledged, acted upon.
        b.eval("document.querySelector('button[data-op=pause]').click()")
        assert b.wait_for(f"{text('reply')} === 'pause: accepted'")
        assert b.wait_for(f"{text('st-paused')} === 'yes'")
        # A goto to a node the robot does not have: refused, with the robot's reason.
        b.eval("document.getElementById('goto-node').value = '42'")
        b.eval("document.querySelector('button[data-op=goto]').click()")
        assert b.wait_for(f"{text('reply')}.startsWith('goto: refused')")
        assert "no node 42" in b.eval(text("reply"))
        b.eval("document.getElementById('goto-node').value = '2'")
        b.eval("document.querySelector('button[data-op=goto]').click()")
        assert b.wait_for(f"{text('st-goal')} === '2'")
        assert b.wait_for("document.querySelector('circle.goal').dataset.id === '2'")

        # The robot goes away: its liveliness token goes, and the page says so.
        robot.send("quit")
        assert b.wait_for(f"{text('st-online')} === 'offline'")
    assert monitor.interrupt() == 0


def test_server_refuses_bad_commands_with_a_reason(setup):
    _, _, url = setup

    def post(body: bytes, ctype: str = "application/json") -> tuple[int, dict]:
        req = urllib.request.Request(
            url + "command", data=body, method="POST", headers={"Content-Type": ctype}
        )
        try:
            with urllib.request.urlopen(req, timeout=10) as resp:
                return resp.status, json.loads(resp.read())
        except urllib.error.HTTPError as err:
            return err.code, json.loads(err.read())

    status, out = post(b"{oops")
    assert status == 400 and "not JSON" in out["error"]
    status, out = post(b'{"op": "self_destruct"}')
    assert status == 400 and "op must be one of" in out["error"]
    status, out = post(b'{"op": "goto", "node": 4}')
    assert status == 200 and out["accepted"] is False and "no node 4" in out["reason"]
    status, out = post(b'{"op": "explore"}')
    assert status == 200 and out["accepted"] is True

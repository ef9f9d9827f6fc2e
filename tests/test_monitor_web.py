"""The monitor's web server on its own (no link): routes, the event stream, command validation."""

from __future__ import annotations

import http.client
import json
import threading

import pytest

from tslam.programs.monitor_web import CommandError, MonitorWeb, Notifier, parse_command


class Fake:
    def __init__(self) -> None:
        self.n = 0
        self.sent: list[tuple[str, int | None]] = []

    def snapshot(self) -> dict:
        return {"robot": "r1", "online": True, "state": {"behaviour": f"b{self.n}"},
                "map": {"nodes": [], "edges": []}, "events": [], "gaps": 0}  # fmt: skip

    def command(self, op: str, node: int | None) -> dict:
        self.sent.append((op, node))
        if op == "goto" and node == 99:
            return {"accepted": False, "reason": "no node 99"}
        return {"accepted": True, "reason": ""}


@pytest.fixture
def server():
    fake, notifier = Fake(), Notifier()
    web = MonitorWeb("127.0.0.1", 0, fake.snapshot, fake.command, notifier).start()
    try:
        yield web, fake, notifier
    finally:
        web.close()


def request(web, method, path, body=None, headers=None):
    host, port = web.url.split("//")[1].rstrip("/").split(":")
    conn = http.client.HTTPConnection(host, int(port), timeout=5)
    try:
        conn.request(method, path, body=body, headers=headers or {})
        resp = conn.getresponse()
        return resp.status, resp.getheader("Content-Type"), resp.read()
    finally:
        conn.close()


def post(web, body, ctype="application/json"):
    data = body if isinstance(body, bytes) else json.dumps(body).encode()
    status, _, out = request(web, "POST", "/command", data, {"Content-Type": ctype})
    return status, json.loads(out)


def test_page_and_snapshot(server):
    web, _, _ = server
    status, ctype, body = request(web, "GET", "/")
    assert status == 200 and ctype.startswith("text/html")
    assert b'id="map"' in body and b"EventSource" in body
    status, ctype, body = request(web, "GET", "/view.json")
    assert status == 200 and json.loads(body)["robot"] == "r1"
    status, _, body = request(web, "GET", "/nope")
    assert status == 404 and "no such page" in json.loads(body)["error"]


def test_commands_are_validated_before_sending(server):
    web, fake, _ = server
    assert post(web, {"op": "pause"}) == (200, {"accepted": True, "reason": ""})
    refused = {"accepted": False, "reason": "no node 99"}
    assert post(web, {"op": "goto", "node": 99}) == (200, refused)
    bad = [
        (b"{not json", "not JSON"),
        (b"\xff\xfe", "not JSON"),
        ([1, 2], "JSON object"),
        ({"op": "dance"}, "op must be one of"),
        ({"op": "goto"}, "goto needs"),
        ({"op": "goto", "node": "3"}, "goto needs"),
        ({"op": "goto", "node": True}, "goto needs"),
        ({"op": "goto", "node": -1}, "goto needs"),
        ({"op": "stop", "node": 3}, "takes no node"),
        ({"op": "stop", "extra": 1}, "unknown field"),
    ]
    for body, reason in bad:
        status, out = post(web, body)
        assert status == 400 and reason in out["error"], (body, out)
    status, out = post(web, {"op": "pause"}, ctype="text/plain")
    assert status == 400 and "Content-Type" in out["error"]
    status, _, out = request(web, "POST", "/command", b"", {"Content-Type": "application/json"})
    assert status == 400
    # Only the two valid commands reached the link.
    assert fake.sent == [("pause", None), ("goto", 99)]


def test_foreign_host_header_is_refused(server):
    web, _, _ = server
    status, _, _ = request(web, "GET", "/view.json", headers={"Host": "evil.example:80"})
    assert status == 403
    status, _, _ = request(
        web, "POST", "/command", b'{"op": "stop"}',
        {"Host": "evil.example", "Content-Type": "application/json"},
    )  # fmt: skip
    assert status == 403
    for host in ("localhost:8080", "127.0.0.1:1234", "[::1]:80", "192.168.1.7"):
        status, _, _ = request(web, "GET", "/view.json", headers={"Host": host})
        assert status == 200, host


def test_link_failure_is_a_reply_not_a_traceback():
    def boom(op, node):
        raise RuntimeError("session closed")

    web = MonitorWeb("127.0.0.1", 0, Fake().snapshot, boom, Notifier()).start()
    try:
        status, out = post(web, {"op": "stop"})
        assert status == 502 and "session closed" in out["error"]
    finally:
        web.close()


def test_stream_pushes_a_snapshot_on_each_change(server):
    web, fake, notifier = server
    host, port = web.url.split("//")[1].rstrip("/").split(":")
    conn = http.client.HTTPConnection(host, int(port), timeout=5)
    conn.request("GET", "/events")
    resp = conn.getresponse()
    assert resp.getheader("Content-Type") == "text/event-stream"

    def next_data() -> dict:
        while True:
            line = resp.fp.readline()
            assert line, "stream ended"
            if line.startswith(b"data: "):
                return json.loads(line[6:])

    try:
        assert next_data()["state"]["behaviour"] == "b0"  # the current view at once
        fake.n = 1
        notifier.bump()
        assert next_data()["state"]["behaviour"] == "b1"
        # A burst of changes is coalesced: the stream catches up with the latest.
        for i in range(2, 50):
            fake.n = i
            notifier.bump()
        got = next_data()["state"]["behaviour"]
        while got != "b49":
            got = next_data()["state"]["behaviour"]
    finally:
        conn.close()


def test_close_ends_open_streams():
    fake, notifier = Fake(), Notifier()
    web = MonitorWeb("127.0.0.1", 0, fake.snapshot, fake.command, notifier).start()
    host, port = web.url.split("//")[1].rstrip("/").split(":")
    conn = http.client.HTTPConnection(host, int(port), timeout=5)
    conn.request("GET", "/events")
    resp = conn.getresponse()
    resp.fp.readline()
    closer = threading.Thread(target=web.close)
    closer.start()
    closer.join(timeout=5)
    assert not closer.is_alive()
    conn.close()


def test_parse_command_accepts_the_ops():
    assert parse_command(b'{"op": "goto", "node": 4}') == ("goto", 4)
    assert parse_command(b'{"op": "explore", "node": null}') == ("explore", None)
    with pytest.raises(CommandError):
        parse_command(b'"pause"')

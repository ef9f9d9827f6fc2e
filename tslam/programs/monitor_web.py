"""The monitor's local web page: a stdlib HTTP server pushing the view by Server-Sent Events.

Routes: ``GET /`` the page, ``GET /view.json`` one snapshot, ``GET /events`` the live stream
(one ``data:`` line of JSON per change, changes within ``COALESCE_S`` folded into one push),
``POST /command`` a command (JSON ``{"op": ..., "node": ...}``), answered with the robot's reply.

The server knows nothing of the link: it is given a function that makes a snapshot, one that
sends a command, and a ``Notifier`` that the link's update callback bumps. That keeps it
testable without a network, and the link's threads never block on a slow browser.
"""

from __future__ import annotations

import ipaddress
import json
import socket
import threading
import time
from collections.abc import Callable
from http import HTTPStatus
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from typing import Any

from tslam.programs.monitor_page import PAGE

#: Ops a command may carry; the robot validates again (it is the authority), this only spares
#: the link a message that cannot be right.
OPS = ("pause", "resume", "stop", "goto", "explore")
#: Minimum time between two pushes on one stream: a burst of map changes becomes one redraw.
COALESCE_S = 0.1
#: A comment line this often keeps proxies and the browser from timing out an idle stream,
#: and lets a handler notice that its browser has gone.
KEEPALIVE_S = 5.0
#: Largest command body accepted; a command is a few dozen bytes.
MAX_BODY = 4096

SnapshotFn = Callable[[], dict[str, Any]]
#: (op, node) -> {"accepted": bool, "reason": str, ...}
CommandFn = Callable[[str, "int | None"], dict[str, Any]]


class Notifier:
    """A change counter that threads can wait on; ``bump`` is cheap enough for zenoh callbacks."""

    def __init__(self) -> None:
        self._cond = threading.Condition()
        self._version = 0
        self._closed = False

    def bump(self) -> None:
        with self._cond:
            self._version += 1
            self._cond.notify_all()

    def close(self) -> None:
        with self._cond:
            self._closed = True
            self._cond.notify_all()

    @property
    def version(self) -> int:
        return self._version

    @property
    def closed(self) -> bool:
        return self._closed

    def wait_newer(self, seen: int, timeout: float) -> int:
        """The version once it differs from ``seen`` (or on timeout or close: whatever it is)."""
        with self._cond:
            self._cond.wait_for(lambda: self._version != seen or self._closed, timeout)
            return self._version


class CommandError(ValueError):
    """A posted command that cannot be sent; the text says why (HTTP 400)."""


def parse_command(body: bytes) -> tuple[str, int | None]:
    """Validate a posted command body; return (op, node) or raise ``CommandError``."""
    try:
        data = json.loads(body.decode("utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise CommandError(f"body is not JSON: {exc}") from None
    if not isinstance(data, dict):
        raise CommandError('body must be a JSON object like {"op": "pause"}')
    unknown = set(data) - {"op", "node"}
    if unknown:
        raise CommandError(f"unknown field(s): {', '.join(sorted(unknown))}")
    op = data.get("op")
    if op not in OPS:
        raise CommandError(f"op must be one of {', '.join(OPS)}; got {op!r}")
    node = data.get("node")
    if op == "goto":
        # bool is an int in Python but never a node id.
        if not isinstance(node, int) or isinstance(node, bool) or node < 0:
            raise CommandError(f'goto needs "node": a node id (an integer >= 0); got {node!r}')
    elif node is not None:
        raise CommandError(f"{op} takes no node")
    return op, node


class _Server(ThreadingHTTPServer):
    # Streams are open for as long as a page is: never let one hold up shutdown.
    daemon_threads = True
    allow_reuse_address = True

    snapshot_fn: SnapshotFn
    command_fn: CommandFn
    notifier: Notifier


class _Server6(_Server):
    address_family = socket.AF_INET6


class _Handler(BaseHTTPRequestHandler):
    server: _Server
    server_version = "tslam-monitor"

    def log_message(self, format: str, *args: Any) -> None:
        pass  # the terminal belongs to the user, not to an access log

    # -- helpers ---------------------------------------------------------------------------
    def _send(self, status: HTTPStatus, body: bytes, ctype: str) -> None:
        self.send_response(status)
        self.send_header("Content-Type", ctype)
        self.send_header("Content-Length", str(len(body)))
        self.send_header("Cache-Control", "no-store")
        self.end_headers()
        self.wfile.write(body)

    def _json(self, status: HTTPStatus, obj: Any) -> None:
        self._send(status, json.dumps(obj).encode(), "application/json")

    def _host_ok(self) -> bool:
        # A page on another site must not reach this server through DNS rebinding: the Host
        # header must be an address literal, localhost, or the name we were bound to.
        host = (self.headers.get("Host") or "").strip()
        host = host[1:].split("]")[0] if host.startswith("[") else host.rsplit(":", 1)[0]
        if host in {self.server.server_address[0], "localhost"}:
            return True
        try:
            ipaddress.ip_address(host)
        except ValueError:
            return False
        return True

    # -- routes ----------------------------------------------------------------------------
    def do_GET(self) -> None:
        if not self._host_ok():
            self._json(HTTPStatus.FORBIDDEN, {"error": "unexpected Host header"})
            return
        path = self.path.split("?", 1)[0]
        if path in ("/", "/index.html"):
            self._send(HTTPStatus.OK, PAGE.encode(), "text/html; charset=utf-8")
        elif path == "/view.json":
            self._json(HTTPStatus.OK, self.server.snapshot_fn())
        elif path == "/events":
            self._stream()
        else:
            self._json(HTTPStatus.NOT_FOUND, {"error": f"no such page: {path}"})

    def do_POST(self) -> None:
        if not self._host_ok():
            self._json(HTTPStatus.FORBIDDEN, {"error": "unexpected Host header"})
            return
        if self.path != "/command":
            self._json(HTTPStatus.NOT_FOUND, {"error": f"no such endpoint: {self.path}"})
            return
        # Requiring JSON makes a cross-site form post impossible (it would need a CORS
        # preflight, which this server never grants).
        ctype = (self.headers.get("Content-Type") or "").split(";")[0].strip().lower()
        if ctype != "application/json":
            self._json(HTTPStatus.BAD_REQUEST, {"error": "Content-Type must be application/json"})
            return
        try:
            length = int(self.headers.get("Content-Length") or "0")
        except ValueError:
            length = -1
        if not 0 < length <= MAX_BODY:
            self._json(HTTPStatus.BAD_REQUEST, {"error": f"body must be 1..{MAX_BODY} bytes"})
            return
        try:
            op, node = parse_command(self.rfile.read(length))
        except CommandError as exc:
            self._json(HTTPStatus.BAD_REQUEST, {"error": str(exc)})
            return
        try:
            reply = self.server.command_fn(op, node)
        except Exception as exc:  # the link failing must not become a traceback in the page
            self._json(HTTPStatus.BAD_GATEWAY, {"error": f"command not sent: {exc}"})
            return
        self._json(HTTPStatus.OK, reply)

    def _stream(self) -> None:
        self.send_response(HTTPStatus.OK)
        self.send_header("Content-Type", "text/event-stream")
        self.send_header("Cache-Control", "no-store")
        self.end_headers()
        notifier = self.server.notifier
        seen = -1
        try:
            while not notifier.closed:
                version = notifier.wait_newer(seen, KEEPALIVE_S)
                if notifier.closed:
                    break
                if version == seen:
                    self.wfile.write(b": keepalive\n\n")
                    self.wfile.flush()
                    continue
                seen = version
                data = json.dumps(self.server.snapshot_fn(), separators=(",", ":"))
                self.wfile.write(f"data: {data}\n\n".encode())
                self.wfile.flush()
                time.sleep(COALESCE_S)
        except (BrokenPipeError, ConnectionResetError, TimeoutError):
            pass  # the browser went away


class MonitorWeb:
    """The web server, started on a thread; ``close`` stops it and ends every stream."""

    def __init__(
        self,
        bind: str,
        port: int,
        snapshot_fn: SnapshotFn,
        command_fn: CommandFn,
        notifier: Notifier,
    ) -> None:
        cls = _Server6 if ":" in bind else _Server
        self._server = cls((bind, port), _Handler)
        self._server.snapshot_fn = snapshot_fn
        self._server.command_fn = command_fn
        self._server.notifier = notifier
        self._notifier = notifier
        self._thread = threading.Thread(
            target=self._server.serve_forever, kwargs={"poll_interval": 0.2},
            name="monitor-web", daemon=True,
        )  # fmt: skip

    @property
    def url(self) -> str:
        host, port = self._server.server_address[:2]
        host = f"[{host}]" if ":" in str(host) else host
        return f"http://{host}:{port}/"

    def start(self) -> MonitorWeb:
        self._thread.start()
        return self

    def close(self) -> None:
        self._notifier.close()
        self._server.shutdown()
        self._server.server_close()
        self._thread.join(timeout=2.0)

    def __enter__(self) -> MonitorWeb:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.close()

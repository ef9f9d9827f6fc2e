"""Helpers for the link's cross-process tests: child processes that are always reaped, a TCP
relay whose connections can be cut and restored, and polling with generous deadlines (the
tests never depend on how fast the machine is, only on things happening eventually)."""

from __future__ import annotations

import contextlib
import os
import queue
import signal
import socket
import subprocess
import sys
import threading
import time
from collections.abc import Callable
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
DEPLOY = ROOT / "deploy" / "zenoh"
#: Generous: a loaded 2-core CI machine may be slow, and a passing test never waits it out.
DEADLINE_S = 30.0


def wait_until(pred: Callable[[], object], timeout_s: float = DEADLINE_S, every_s: float = 0.05):
    """Poll ``pred`` until it returns something true; that value, or None at the deadline."""
    end = time.monotonic() + timeout_s
    while True:
        v = pred()
        if v:
            return v
        if time.monotonic() > end:
            return None
        time.sleep(every_s)


class Child:
    """A ``python -m MODULE`` child whose stdout lines are collected by a thread."""

    def __init__(self, module: str, args: list[str]) -> None:
        env = dict(os.environ, PYTHONPATH=str(ROOT), RUST_LOG="off")
        self.proc = subprocess.Popen(
            [sys.executable, "-m", module, *args],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            env=env,
            cwd=ROOT,
        )
        self.lines: queue.Queue[str] = queue.Queue()
        self.stderr: list[str] = []
        self.ready_line = ""
        threading.Thread(
            target=self._pump, args=(self.proc.stdout, self.lines.put), daemon=True
        ).start()
        threading.Thread(
            target=self._pump, args=(self.proc.stderr, self.stderr.append), daemon=True
        ).start()

    @staticmethod
    def _pump(stream, sink) -> None:
        for line in stream:
            sink(line.rstrip("\n"))

    def wait_line(self, prefix: str, timeout_s: float = DEADLINE_S) -> str:
        end = time.monotonic() + timeout_s
        while time.monotonic() < end:
            try:
                line = self.lines.get(timeout=0.1)
            except queue.Empty:
                if self.proc.poll() is not None:
                    break
                continue
            if line.startswith(prefix):
                return line
        raise AssertionError(
            f"no {prefix!r} line from {self.proc.args}; exit {self.proc.poll()}; "
            f"stderr: {' | '.join(self.stderr[-10:])}"
        )

    def exit_code(self, timeout_s: float) -> int:
        """Its exit code once it has exited; a failure naming its last words if it has not."""
        try:
            return self.proc.wait(timeout_s)
        except subprocess.TimeoutExpired:
            raise AssertionError(
                f"{self.proc.args} still running after {timeout_s} s; "
                f"stderr: {' | '.join(self.stderr[-10:])}"
            ) from None

    def signal(self, sig: int) -> None:
        if self.proc.poll() is None:
            self.proc.send_signal(sig)

    def stop(self, timeout_s: float = 10.0) -> int | None:
        """SIGCONT (in case it is stopped), SIGTERM, then SIGKILL; the exit code."""
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGCONT)
            self.proc.send_signal(signal.SIGTERM)
            try:
                self.proc.wait(timeout_s)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait(10)
        return self.proc.returncode


class Children:
    """Every child a test starts; ``close()`` (from a fixture's teardown) reaps them all."""

    def __init__(self) -> None:
        self.all: list[Child] = []

    def start(self, module: str, *args: str, ready: str | None = "ready") -> Child:
        child = Child(module, list(args))
        self.all.append(child)
        if ready is not None:
            child.ready_line = child.wait_line(ready)
        return child

    def robot(self, *args: str) -> Child:
        return self.start("tslam.link.demo_robot", *args)

    def close(self) -> None:
        for child in self.all:
            child.stop()


class Relay:
    """A TCP relay on 127.0.0.1 to ``target_port``; ``cut()`` drops every connection and
    refuses new ones until ``restore()``: a link that goes down while both ends stay up."""

    def __init__(self, target_port: int) -> None:
        self.target = target_port
        self._srv = socket.socket()
        self._srv.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        self._srv.bind(("127.0.0.1", 0))
        self._srv.listen(16)
        self._srv.settimeout(0.1)
        self.port = self._srv.getsockname()[1]
        self._up = threading.Event()
        self._up.set()
        self._closed = False
        self._lock = threading.Lock()
        self._socks: list[socket.socket] = []
        threading.Thread(target=self._accept, daemon=True).start()

    def _accept(self) -> None:
        while not self._closed:
            try:
                a, _ = self._srv.accept()
            except (TimeoutError, OSError):
                continue
            if not self._up.is_set():
                a.close()
                continue
            try:
                b = socket.create_connection(("127.0.0.1", self.target), timeout=2)
            except OSError:
                a.close()
                continue
            with self._lock:
                self._socks += [a, b]
            for src, dst in ((a, b), (b, a)):
                threading.Thread(target=self._pipe, args=(src, dst), daemon=True).start()

    def _pipe(self, src: socket.socket, dst: socket.socket) -> None:
        try:
            while True:
                data = src.recv(65536)
                if not data:
                    break
                dst.sendall(data)
        except OSError:
            pass
        for s in (src, dst):
            with contextlib.suppress(OSError):
                s.shutdown(socket.SHUT_RDWR)

    def cut(self) -> None:
        self._up.clear()
        with self._lock:
            socks, self._socks = self._socks, []
        for s in socks:
            try:
                s.shutdown(socket.SHUT_RDWR)
                s.close()
            except OSError:
                pass

    def restore(self) -> None:
        self._up.set()

    def close(self) -> None:
        self._closed = True
        self.cut()
        self._srv.close()

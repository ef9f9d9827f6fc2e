"""Processes for the monitor's cross-process tests: a fake robot and ``tslam monitor`` itself.

Every process is started in its own session and killed in ``close`` however the test ended,
and every wait is bounded.
"""

from __future__ import annotations

import os
import queue
import re
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

from tslam.link.config import free_port

ROOT = Path(__file__).resolve().parent.parent


class Proc:
    """A child process whose stdout lines are read on a thread, for ``expect``."""

    def __init__(self, argv: list[str], *, stdin: bool = False) -> None:
        env = dict(os.environ, PYTHONUNBUFFERED="1", ZENOH_LOG="error")
        self.argv = argv
        self.proc = subprocess.Popen(
            argv, cwd=ROOT, env=env, text=True,
            stdin=subprocess.PIPE if stdin else subprocess.DEVNULL,
            stdout=subprocess.PIPE, stderr=subprocess.PIPE, start_new_session=True,
        )  # fmt: skip
        self.lines: queue.Queue[str | None] = queue.Queue()
        self.seen: list[str] = []
        self._reader = threading.Thread(target=self._read, daemon=True)
        self._reader.start()

    def _read(self) -> None:
        assert self.proc.stdout is not None
        for line in self.proc.stdout:
            self.lines.put(line.rstrip("\n"))
        self.lines.put(None)

    def expect(self, pattern: str, timeout_s: float = 15.0) -> re.Match[str]:
        """The first new stdout line matching ``pattern``; AssertionError on timeout or exit."""
        deadline = time.monotonic() + timeout_s
        rx = re.compile(pattern)
        while True:
            left = deadline - time.monotonic()
            if left <= 0:
                raise AssertionError(
                    f"{self.argv[-8:]} never printed {pattern!r}: {self.seen[-20:]}"
                )
            try:
                line = self.lines.get(timeout=left)
            except queue.Empty:
                continue
            if line is None:
                err = self.proc.stderr.read() if self.proc.stderr else ""
                raise AssertionError(
                    f"{self.argv[-8:]} exited ({self.proc.wait()}) before {pattern!r}: "
                    f"{self.seen[-20:]} {err[-2000:]}"
                )
            self.seen.append(line)
            m = rx.search(line)
            if m:
                return m

    def send(self, line: str) -> None:
        assert self.proc.stdin is not None
        self.proc.stdin.write(line + "\n")
        self.proc.stdin.flush()

    def interrupt(self, timeout_s: float = 10.0) -> int:
        """SIGINT (Ctrl-C), then its exit code; it must exit on its own in time."""
        self.proc.send_signal(signal.SIGINT)
        return self.proc.wait(timeout=timeout_s)

    def close(self) -> None:
        if self.proc.poll() is None:
            self.proc.terminate()
            try:
                self.proc.wait(timeout=5)
            except subprocess.TimeoutExpired:
                os.killpg(self.proc.pid, signal.SIGKILL)
                self.proc.wait(timeout=5)
        for f in (self.proc.stdin, self.proc.stdout, self.proc.stderr):
            if f is not None:
                f.close()


def start_robot(robot: str = "r1", nodes: int = 4, port: int | None = None) -> tuple[Proc, int]:
    """A fake robot listening on 127.0.0.1; returns it (ready) and its port."""
    port = port or free_port()
    p = Proc(
        [sys.executable, "-m", "tests.monitor_fake_robot", "--robot", robot,
         "--listen", str(port), "--nodes", str(nodes)],
        stdin=True,
    )  # fmt: skip
    try:
        p.expect("^ready$", 20.0)
    except BaseException:
        p.close()
        raise
    return p, port


#: Not ``-m tslam.programs.cli``: run as ``__main__``, cli's ``UserError`` would be a second
#: class, not the one the commands raise, and a user error would end in a traceback.
_MAIN = "import sys; from tslam.programs.cli import main; sys.exit(main())"


def monitor_argv(*args: str) -> list[str]:
    return [sys.executable, "-c", _MAIN, "monitor", *args]


def run_monitor(*args: str, timeout_s: float = 30.0) -> subprocess.CompletedProcess[str]:
    """``tslam monitor ARGS`` to completion (bounded)."""
    env = dict(os.environ, ZENOH_LOG="error")
    return subprocess.run(
        monitor_argv(*args), cwd=ROOT, env=env, text=True, capture_output=True,
        timeout=timeout_s, stdin=subprocess.DEVNULL,
    )  # fmt: skip

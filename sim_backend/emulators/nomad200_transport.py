"""The robot's end of the line: a pseudo-terminal or a TCP socket on loopback, that can vanish.

A pty is what a USB serial adapter looks like to the driver (``/dev/pts/N``, opened with
termios), so the driver's serial code runs for real. The emulator keeps the slave end open
itself, so the master never reports a hang-up while the driver is away between opens, and
sets it raw so no byte is translated. A pty cannot come back at the same path, so ``link``
names a symbolic link kept pointing at the current one: a driver opening the link finds the
new pty after a reappearance.

TCP is the Nomad's other host link (the on-board daemon listens on port 65001); the driver
reaches it as ``socket://127.0.0.1:PORT``. One client at a time; a new connection replaces the
old one. After vanishing, the listener comes back on the same port.

Every method is non-blocking; ``fileno`` always returns something ``select`` can wait on (an
idle pipe while the line is down).
"""

from __future__ import annotations

import contextlib
import errno
import os
import select
import socket
import tty
from pathlib import Path
from typing import Protocol

WRITE_WAIT_S = 0.5


class Transport(Protocol):
    def fileno(self) -> int: ...

    def poll(self) -> None:
        """Accept a waiting connection, if the transport takes them."""

    def read(self) -> bytes: ...

    def write(self, data: bytes) -> None: ...

    def disappear(self) -> None: ...

    def reappear(self) -> None: ...

    def describe(self) -> dict[str, object]: ...

    def close(self) -> None: ...


def _write_all(fd: int, data: bytes) -> None:
    """Write within a bounded wait; what does not fit goes nowhere, as on a line nobody reads."""
    view = memoryview(data)
    while view:
        try:
            n = os.write(fd, view)
        except BlockingIOError:
            _, ready, _ = select.select([], [fd], [], WRITE_WAIT_S)
            if not ready:
                return
            continue
        view = view[n:]


class _Idle:
    """A pipe nobody writes to: something to ``select`` on while the line is down."""

    def __init__(self) -> None:
        self.r, self.w = os.pipe()

    def close(self) -> None:
        for fd in (self.r, self.w):
            with contextlib.suppress(OSError):
                os.close(fd)


class PtyTransport:
    def __init__(self, link: str | os.PathLike[str] | None = None) -> None:
        self.link = Path(link) if link is not None else None
        self._idle = _Idle()
        self._master = -1
        self._slave = -1
        self.path = ""
        self._open()

    def _open(self) -> None:
        self._master, self._slave = os.openpty()
        tty.setraw(self._slave)
        os.set_blocking(self._master, False)
        self.path = os.ttyname(self._slave)
        if self.link is not None:
            tmp = self.link.with_name(self.link.name + ".new")
            with contextlib.suppress(FileNotFoundError):
                tmp.unlink()
            tmp.symlink_to(self.path)
            tmp.replace(self.link)  # atomic: a driver never sees the link missing mid-swap

    @property
    def up(self) -> bool:
        return self._master >= 0

    def fileno(self) -> int:
        return self._master if self.up else self._idle.r

    def poll(self) -> None:
        pass

    def read(self) -> bytes:
        if not self.up:
            return b""
        try:
            return os.read(self._master, 4096)
        except BlockingIOError:
            return b""
        except OSError as exc:
            if exc.errno == errno.EIO:  # no slave open: nothing to read
                return b""
            raise

    def write(self, data: bytes) -> None:
        if self.up:
            _write_all(self._master, data)

    def disappear(self) -> None:
        if not self.up:
            return
        for fd in (self._master, self._slave):
            with contextlib.suppress(OSError):
                os.close(fd)
        self._master = self._slave = -1
        if self.link is not None:
            with contextlib.suppress(FileNotFoundError):
                self.link.unlink()

    def reappear(self) -> None:
        if not self.up:
            self._open()

    def describe(self) -> dict[str, object]:
        port = str(self.link) if self.link is not None else self.path
        return {"transport": "pty", "port": port, "pty": self.path}

    def close(self) -> None:
        self.disappear()
        self._idle.close()


class TcpTransport:
    def __init__(self, host: str = "127.0.0.1", port: int = 0) -> None:
        self.host = host
        self._idle = _Idle()
        self._listener: socket.socket | None = None
        self._conn: socket.socket | None = None
        self.port = port
        self._listen()

    def _listen(self) -> None:
        s = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        s.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        s.bind((self.host, self.port))
        s.listen(1)
        s.setblocking(False)
        self.port = s.getsockname()[1]
        self._listener = s

    def fileno(self) -> int:
        if self._conn is not None:
            return self._conn.fileno()
        if self._listener is not None:
            return self._listener.fileno()
        return self._idle.r

    def poll(self) -> None:
        if self._listener is None:
            return
        try:
            conn, _ = self._listener.accept()
        except (BlockingIOError, InterruptedError):
            return
        if self._conn is not None:
            self._conn.close()
        conn.setblocking(False)
        conn.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        self._conn = conn

    def read(self) -> bytes:
        if self._conn is None:
            self.poll()  # the listener was readable: a client is waiting
            return b""
        try:
            data = self._conn.recv(4096)
        except (BlockingIOError, InterruptedError):
            return b""
        except OSError:
            data = b""
        if not data:  # the client went away; wait for the next one
            self._conn.close()
            self._conn = None
        return data

    def write(self, data: bytes) -> None:
        if self._conn is None:
            return
        try:
            _write_all(self._conn.fileno(), data)
        except OSError:
            self._conn.close()
            self._conn = None

    def disappear(self) -> None:
        for s in (self._conn, self._listener):
            if s is not None:
                s.close()
        self._conn = self._listener = None

    def reappear(self) -> None:
        if self._listener is None:
            self._listen()

    def describe(self) -> dict[str, object]:
        return {
            "transport": "tcp",
            "port": f"socket://{self.host}:{self.port}",
            "tcp": f"{self.host}:{self.port}",
        }

    def close(self) -> None:
        self.disappear()
        self._idle.close()

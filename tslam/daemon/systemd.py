"""systemd's notification protocol (sd_notify(3)): readiness, watchdog pings, stopping.

Nothing happens when the daemon is not run by systemd (no ``NOTIFY_SOCKET``), so the same
binary runs by hand, in tests and under ``Type=notify``.
"""

from __future__ import annotations

import contextlib
import os
import socket


class Notifier:
    def __init__(self, environ: dict[str, str] | None = None) -> None:
        env = os.environ if environ is None else environ
        addr = env.get("NOTIFY_SOCKET", "")
        # A leading '@' names a socket in the abstract namespace (a NUL byte on the wire).
        self._addr = ("\0" + addr[1:]) if addr.startswith("@") else addr
        usec = env.get("WATCHDOG_USEC", "")
        pid = env.get("WATCHDOG_PID", "")
        mine = not pid or pid == str(os.getpid())
        #: How often systemd wants a ping (half its WatchdogSec), or None without a watchdog.
        self.watchdog_interval_s = int(usec) / 2e6 if usec.isdigit() and mine else None

    @property
    def enabled(self) -> bool:
        return bool(self._addr)

    def notify(self, *fields: str) -> None:
        if not self._addr:
            return
        msg = "\n".join(fields).encode()
        # systemd gone (shutting down): nothing to tell, and no reason to stop the robot for.
        with socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM) as s, contextlib.suppress(OSError):
            s.sendto(msg, self._addr)

    def ready(self, status: str) -> None:
        self.notify("READY=1", f"STATUS={status}")

    def ping(self) -> None:
        self.notify("WATCHDOG=1")

    def status(self, status: str) -> None:
        self.notify(f"STATUS={status}")

    def stopping(self) -> None:
        self.notify("STOPPING=1")

"""A stop request that a signal handler can raise without deadlocking the process.

A Python signal handler runs in the main thread between two bytecodes, possibly while that
thread is inside ``threading.Event.wait`` holding the event's internal lock. A handler that
calls ``Event.set()`` then blocks on that same lock forever: the daemon hung on SIGTERM this way
in 2 of 20 runs of its late-monitor test. ``print`` from a handler can likewise fail with a
reentrant write on a buffered stream. So setting a ``StopFlag`` takes no lock and prints
nothing: it assigns an attribute and writes a byte to a pipe, and waiting is ``select`` on that
pipe, which a signal interrupts and which wakes as soon as the byte is written.
"""

from __future__ import annotations

import contextlib
import os
import select
import signal
from collections.abc import Callable, Iterator
from types import FrameType


class StopFlag:
    """Set once (from any thread or a signal handler), then stays set; ``reason`` says why."""

    def __init__(self) -> None:
        self._r, self._w = os.pipe()
        os.set_blocking(self._r, False)
        os.set_blocking(self._w, False)
        self.reason: str | None = None

    def set(self, reason: str) -> None:
        if self.reason is None:
            self.reason = reason
        # A full pipe (the byte is already there) or a closed one needs nothing more.
        with contextlib.suppress(OSError):
            os.write(self._w, b"!")

    def is_set(self) -> bool:
        return self.reason is not None

    def wait(self, timeout_s: float | None) -> bool:
        """Wait until set or ``timeout_s`` has passed; whether it is set."""
        if self.reason is None and self._r >= 0:
            with contextlib.suppress(OSError, ValueError):
                select.select([self._r], [], [], timeout_s)
        return self.reason is not None

    def fileno(self) -> int:
        return self._r

    def close(self) -> None:
        fds, (self._r, self._w) = (self._r, self._w), (-1, -1)
        for fd in fds:
            if fd >= 0:
                with contextlib.suppress(OSError):
                    os.close(fd)


@contextlib.contextmanager
def stop_on_signals(
    stop: Callable[[str], None],
    signals: tuple[signal.Signals, ...] = (signal.SIGTERM, signal.SIGINT),
) -> Iterator[None]:
    """While inside, each of ``signals`` calls ``stop`` with the signal's name; ``stop`` must be
    safe in a signal handler (``StopFlag.set`` is). The previous handlers come back on exit."""

    def handler(signum: int, frame: FrameType | None) -> None:
        stop(signal.Signals(signum).name)

    old = {s: signal.signal(s, handler) for s in signals}
    try:
        yield
    finally:
        for s, h in old.items():
            signal.signal(s, h)

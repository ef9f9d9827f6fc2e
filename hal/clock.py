"""Clocks. Backends own one; loops read time from it rather than from the system.

On hardware, time passes by itself (``MonotonicClock``). In simulation, ``sleep`` is what makes
time pass: it steps the simulator, so a loop written against this protocol runs as fast as
the processor allows and is reproducible.
"""

from __future__ import annotations

import time
from typing import Protocol


class Clock(Protocol):
    def now(self) -> float:
        """Seconds since an arbitrary origin, never decreasing."""
        ...

    def sleep(self, seconds: float) -> None:
        """Let ``seconds`` pass."""
        ...


class MonotonicClock:
    """The host's monotonic clock, for real hardware."""

    def now(self) -> float:
        return time.monotonic()

    def sleep(self, seconds: float) -> None:
        if seconds > 0:
            time.sleep(seconds)

"""Stops the drive when the control loop stalls.

The loop beats once per cycle; a thread of its own checks the beats against the wall clock
(the loop's clock may be simulated, and a stalled loop is exactly what does not advance it).
A stall inside a driver call that holds the device is the robot's own watchdog's to catch:
the Nomad 200 stops itself when no motion command arrives within ``conf_tm``.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable


class Watchdog:
    def __init__(
        self,
        limit_s: float,
        on_stall: Callable[[float], None],
        monotonic: Callable[[], float] = time.monotonic,
    ) -> None:
        self.limit_s = limit_s
        self._on_stall = on_stall
        self._mono = monotonic
        self._last = monotonic()
        self._tripped = False
        self.stalls = 0
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="tslam-watchdog", daemon=True)

    def start(self) -> None:
        self._last = self._mono()
        self._thread.start()

    def beat(self) -> None:
        self._last = self._mono()
        self._tripped = False

    def check(self) -> bool:
        """Trip if the last beat is too old; True when it tripped now."""
        stalled = self._mono() - self._last
        if stalled <= self.limit_s or self._tripped:
            return False
        self._tripped = True
        self.stalls += 1
        self._on_stall(stalled)
        return True

    def close(self) -> None:
        self._stop.set()
        if self._thread.is_alive():
            self._thread.join(timeout=2.0)

    def _run(self) -> None:
        while not self._stop.wait(self.limit_s / 4):
            self.check()

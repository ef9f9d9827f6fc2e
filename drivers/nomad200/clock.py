"""The driver's clock: the robot's controller clock, as last heard in a state reply.

Every stamp the robot sends (the state's clock, each sonar's sensing time) is on its controller
clock, so making that the backend's clock puts stamps and ``now()`` on one time base with no
offset to estimate. Between replies:

* real time (a robot, or an emulator serving in real time): ``now()`` runs on from the last reply
  at ``time_scale`` controller seconds per host second (never backwards); ``sleep`` sleeps;
* lockstep (an emulator whose time passes only when asked): ``now()`` is exactly the last
  reply's clock, and ``sleep(dt)`` asks the emulator to run to ``now() + dt`` (a round trip
  whose reply carries the new state), so a control loop through the emulator advances simulated
  time just as ``SimClock.sleep`` does in process.

The controller counts milliseconds in 32 bits; readings are unwrapped (49.7 days per turn).
"""

from __future__ import annotations

import time
from collections.abc import Callable

WRAP_MS = 1 << 32
HALF_WRAP_MS = 1 << 31


class ControllerClock:
    """``hal.clock.Clock`` for the Nomad 200 driver."""

    def __init__(
        self,
        *,
        lockstep: bool,
        time_scale: float = 1.0,
        step: Callable[[float], None] | None = None,
        monotonic: Callable[[], float] = time.monotonic,
        host_sleep: Callable[[float], None] = time.sleep,
    ) -> None:
        self.lockstep = lockstep
        self.time_scale = time_scale
        self._step = step
        self._monotonic = monotonic
        self._host_sleep = host_sleep
        self._last_ms: int | None = None  # unwrapped
        self._heard_at = 0.0  # host time of the last reply
        self._returned = 0.0

    @property
    def synced(self) -> bool:
        """True once a reply has set the clock."""
        return self._last_ms is not None

    @property
    def last_ms(self) -> int:
        """The last controller time heard, unwrapped, in ms (0 before any reply)."""
        return self._last_ms or 0

    def unwrap(self, raw_ms: int) -> int:
        """A raw 32-bit controller time as an unwrapped one, taken to be near the last heard."""
        if self._last_ms is None:
            return raw_ms
        base = self._last_ms - self._last_ms % WRAP_MS
        value = base + raw_ms
        if value < self._last_ms - HALF_WRAP_MS:
            value += WRAP_MS
        elif value > self._last_ms + HALF_WRAP_MS:
            value -= WRAP_MS
        return value

    def observe(self, raw_ms: int) -> float:
        """Record a reply's controller clock; returns it in seconds (unwrapped)."""
        value = self.unwrap(raw_ms)
        if self._last_ms is None or value >= self._last_ms:
            self._last_ms = value
            self._heard_at = self._monotonic()
        return value / 1000.0

    def seconds(self, raw_ms: int) -> float:
        """A controller stamp (a sensing time, say) in seconds, unwrapped near the last heard."""
        return self.unwrap(raw_ms) / 1000.0

    def now(self) -> float:
        if self._last_ms is None:
            return 0.0
        t = self._last_ms / 1000.0
        if not self.lockstep:
            t += (self._monotonic() - self._heard_at) * self.time_scale
        self._returned = max(self._returned, t)
        return self._returned

    def sleep(self, seconds: float) -> None:
        if not seconds > 0:
            return
        if self.lockstep:
            if self._step is None:
                raise RuntimeError("lockstep clock has no way to step the emulator")
            self._step(seconds)
        else:
            self._host_sleep(seconds / self.time_scale)

"""What a bad serial line does to the Nomad 200's replies, injected on purpose and seeded.

Each reply, once the first ``after_requests`` requests have been answered cleanly, meets one
draw of a seeded RNG: with probability ``drop`` it is not sent, ``corrupt`` one byte from TYPE
to CHK is changed, ``truncate`` only a prefix is sent, ``garbage`` random bytes go before it;
independently, ``delay`` holds it back ``delay_s`` seconds (host time). The request itself is
always carried out, as on a real line where only the answer is lost, so a driver that gives up
still finds the robot doing what it last asked (a stop included).

"Disappearing" (the link closing) is a matter for the transport; its triggers live here too so
one object carries every fault option.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class FaultConfig:
    drop: float = 0.0
    corrupt: float = 0.0
    truncate: float = 0.0
    garbage: float = 0.0
    delay: float = 0.0
    delay_s: float = 0.5
    #: Requests answered cleanly before any fault (e.g. let configuration through).
    after_requests: int = 0
    #: Close the link once simulated time reaches this many seconds (checked when a request
    #: arrives: that request finds the line gone, so no answer already sent is lost).
    disappear_after_s: float = math.inf
    #: Close the link after answering this many requests (the next one finds it gone).
    disappear_after_requests: int | None = None
    #: Open it again after this many host seconds (never if None).
    reappear_after_s: float | None = None
    seed: int = 0

    def __post_init__(self) -> None:
        for name in ("drop", "corrupt", "truncate", "garbage", "delay"):
            value = getattr(self, name)
            if not 0.0 <= value <= 1.0:
                raise ValueError(f"fault probability {name} must be in 0..1, got {value}")
        total = self.drop + self.corrupt + self.truncate + self.garbage
        if total > 1.0 + 1e-9:
            raise ValueError(
                f"drop + corrupt + truncate + garbage must not exceed 1, got {total:g}"
            )
        if self.delay_s < 0 or self.after_requests < 0:
            raise ValueError("delay_s and after_requests must not be negative")
        if self.reappear_after_s is not None and self.reappear_after_s < 0:
            raise ValueError("reappear_after_s must not be negative")

    @property
    def any_reply_fault(self) -> bool:
        return self.drop + self.corrupt + self.truncate + self.garbage + self.delay > 0


class FaultInjector:
    """Turns one reply frame into what actually goes on the line, and when."""

    def __init__(self, config: FaultConfig) -> None:
        self.config = config
        self._rng = np.random.default_rng(config.seed)
        self.injected: dict[str, int] = {}

    def _count(self, kind: str) -> None:
        self.injected[kind] = self.injected.get(kind, 0) + 1

    def apply(self, frame: bytes, request_number: int) -> tuple[bytes, float] | None:
        """``(bytes to send, delay in s)``, or None to drop the reply."""
        c = self.config
        if request_number <= c.after_requests or not c.any_reply_fault:
            return frame, 0.0
        u = self._rng.random()
        out = frame
        if u < c.drop:
            self._count("drop")
            return None
        u -= c.drop
        if u < c.corrupt:
            self._count("corrupt")
            data = bytearray(frame)
            # A byte from TYPE to CHK: what the checksum exists to catch. A broken start, length
            # or end byte reads as garbage or truncation, injected on their own.
            k = int(self._rng.integers(3, len(data) - 1))
            data[k] ^= int(self._rng.integers(1, 256))
            out = bytes(data)
        elif u - c.corrupt < c.truncate:
            self._count("truncate")
            out = frame[: int(self._rng.integers(1, len(frame)))]
        elif u - c.corrupt - c.truncate < c.garbage:
            self._count("garbage")
            noise = self._rng.integers(0, 256, int(self._rng.integers(1, 16)), dtype=np.uint8)
            out = bytes(noise) + frame
        delay = 0.0
        if c.delay and self._rng.random() < c.delay:
            self._count("delay")
            delay = c.delay_s
        return out, delay

"""The board's heartbeat as a small state machine with time passed in, so it is tested without
threads or sleeps.

The host sends CONNECT every ``interval_s``; the board answers each with a CONNECT reply. A
CONNECT still unanswered when the next one is due is a missed reply; after ``allowed_misses``
missed replies in a row the board counts as lost, and stays lost: a board that vanished while
the robot moved must not silently come back with readings the robot did not wait for.
"""

from __future__ import annotations

import math

from drivers.can_sonar.codec import CONNECT_INTERVAL_S, CONNECT_TIMEOUT_INTERVALS


class Heartbeat:
    """When to send CONNECT, and whether the board still answers."""

    def __init__(
        self,
        interval_s: float = CONNECT_INTERVAL_S,
        allowed_misses: int = CONNECT_TIMEOUT_INTERVALS,
    ) -> None:
        if not (math.isfinite(interval_s) and interval_s > 0):
            raise ValueError(f"heartbeat interval must be positive, got {interval_s}")
        if allowed_misses < 1:
            raise ValueError(f"allowed misses must be at least 1, got {allowed_misses}")
        self.interval_s = interval_s
        self.allowed_misses = allowed_misses
        self._next_s = -math.inf
        self._awaiting = False
        self._missed = 0
        self._lost = False
        self.last_reply_s: float | None = None
        self.total_missed = 0

    @property
    def lost(self) -> bool:
        return self._lost

    @property
    def missed(self) -> int:
        """Consecutive CONNECTs that went unanswered."""
        return self._missed

    @property
    def next_due_s(self) -> float:
        return self._next_s

    def due(self, now_s: float) -> bool:
        return not self._lost and now_s >= self._next_s

    def sent(self, now_s: float) -> None:
        """A CONNECT went out at ``now_s``; the previous one's reply is now overdue."""
        if self._awaiting:
            self._missed += 1
            self.total_missed += 1
            if self._missed >= self.allowed_misses:
                self._lost = True
        self._awaiting = True
        # Keep the beat regular, but after a long stall (a suspended host) start afresh rather
        # than firing a burst of CONNECTs to catch up.
        nxt = self._next_s + self.interval_s
        self._next_s = nxt if nxt > now_s else now_s + self.interval_s

    def replied(self, now_s: float) -> None:
        """A CONNECT reply arrived (late ones count: the board is alive)."""
        if self._lost:
            return
        self._awaiting = False
        self._missed = 0
        self.last_reply_s = now_s

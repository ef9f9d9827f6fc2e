"""Fault injection for the emulated CAN sonar board, on a seeded RNG so a failure reproduces.

Faults act on what the board sends:

- ``drop``: each frame is lost with this probability;
- ``corrupt``: each frame is damaged with this probability, in a way the protocol can recognise
  (a truncated frame, or a group byte that contradicts the identifier): on a real bus CAN's CRC
  hides every other kind of damage, so these are the corruptions a driver actually meets;
- ``bus_errors``: with this probability a frame is destroyed by a bus error, which the adapter
  reports (an error frame on a python-can virtual bus, BEL on slcan);
- ``heartbeat_stops_after_s``: from this simulated time on, CONNECT goes unanswered (the board
  is otherwise alive, which is the nastiest case for a driver);
- ``wrong_ack_sum``: the final parameter-set acknowledgement carries a wrong byte sum (and the
  board keeps its old parameters, as one that received damaged frames would).
"""

from __future__ import annotations

import math
import random
from dataclasses import dataclass

from drivers.can_sonar.codec import FRAME_LENGTH, Frame, UsBoardCodec


@dataclass(frozen=True)
class BoardFaults:
    drop: float = 0.0
    corrupt: float = 0.0
    bus_errors: float = 0.0
    heartbeat_stops_after_s: float | None = None
    wrong_ack_sum: bool = False

    def __post_init__(self) -> None:
        for name in ("drop", "corrupt", "bus_errors"):
            p = getattr(self, name)
            if not (isinstance(p, int | float) and 0.0 <= p <= 1.0):
                raise ValueError(f"fault probability '{name}' must be between 0 and 1, got {p!r}")
        h = self.heartbeat_stops_after_s
        if h is not None and not (math.isfinite(h) and h >= 0):
            raise ValueError(f"heartbeat stop time must be a time >= 0 s, got {h!r}")


class BusError:
    """Marker for a bus error the adapter reports in place of a frame."""

    __slots__ = ()


BUS_ERROR = BusError()


@dataclass
class FaultCounts:
    dropped: int = 0
    corrupted: int = 0
    bus_errors: int = 0


class FaultInjector:
    """Decides, frame by frame, what reaches the wire."""

    def __init__(self, faults: BoardFaults, codec: UsBoardCodec, seed: int = 0) -> None:
        self.faults = faults
        self.codec = codec
        self.rng = random.Random(seed)
        self.counts = FaultCounts()

    def heartbeat_stopped(self, now_s: float) -> bool:
        h = self.faults.heartbeat_stops_after_s
        return h is not None and now_s >= h

    def outgoing(self, frame: Frame) -> Frame | BusError | None:
        """The frame as it reaches the wire, a bus error, or None (lost)."""
        f = self.faults
        # One draw per fault kind and frame keeps the random sequence independent of which
        # faults are enabled, so adding one does not reshuffle the others.
        u_bus, u_drop, u_corrupt = self.rng.random(), self.rng.random(), self.rng.random()
        if u_bus < f.bus_errors:
            self.counts.bus_errors += 1
            return BUS_ERROR
        if u_drop < f.drop:
            self.counts.dropped += 1
            return None
        if u_corrupt < f.corrupt:
            self.counts.corrupted += 1
            return self._damage(frame)
        return frame

    def _damage(self, frame: Frame) -> Frame:
        offset = frame.arbitration_id - self.codec.base_id
        group = offset - 13
        if 0 <= group <= 3 and self.rng.random() < 0.5:
            # A group byte naming another group than the identifier does.
            other = (group + self.rng.randrange(1, 4)) % 4
            data = bytearray(frame.data)
            data[1] = (data[1] & ~0x03) | other
            return Frame(frame.arbitration_id, bytes(data))
        return Frame(frame.arbitration_id, frame.data[: self.rng.randrange(0, FRAME_LENGTH)])

"""The board's end of a python-can bus: opening it from configuration, frames in and out through
the codec, and counters of everything that went wrong on the way.

Policy for bad input (one place, so the driver and its tests agree):

- a frame that is not this board's (another identifier, an extended or remote frame) is
  *foreign*: skipped and counted, since the bus is shared;
- a frame with this board's identifier that the codec refuses (wrong length, bad group byte,
  a field out of range) or a line the adapter could not parse is *corrupt*: skipped and counted,
  never half-used; the readings it would have refreshed simply age (see ``readings``);
- an error frame is counted as a *bus error*;
- a failed send is counted and retried at the next period (the heartbeat notices a dead link);
- a failed receive means the port or interface went away: ``LinkLostError``.
"""

from __future__ import annotations

import logging
from dataclasses import asdict, dataclass

import can

from drivers.can_sonar.codec import Frame, FrameError, Reply, UsBoardCodec
from hal.clock import Clock
from hal.errors import ConfigurationError, LinkLostError

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class BusSettings:
    """What python-can needs to open the bus; ``interface`` is any python-can interface name."""

    interface: str
    channel: str
    bitrate: int
    #: slcan only: seconds python-can waits after opening the port (None: python-can's default,
    #: 2 s, which adapters that reset on open need; 0 for a pseudo-terminal).
    open_delay_s: float | None = None

    def describe(self) -> str:
        return f"{self.interface} {self.channel}"


def open_bus(settings: BusSettings) -> can.BusABC:
    """Open the bus; configuration mistakes raise ConfigurationError, I/O ones LinkLostError."""
    kwargs: dict[str, object] = {
        "interface": settings.interface,
        "channel": settings.channel,
        "bitrate": settings.bitrate,
    }
    if settings.interface == "slcan" and settings.open_delay_s is not None:
        kwargs["sleep_after_open"] = settings.open_delay_s
    where = settings.describe()
    try:
        return can.Bus(**kwargs)  # type: ignore[arg-type]
    except (can.CanInterfaceNotImplementedError, NotImplementedError, ImportError) as exc:
        raise ConfigurationError(
            f"can-sonar: interface {where} is not available here: {exc}"
        ) from None
    except ValueError as exc:
        raise ConfigurationError(f"can-sonar: cannot open {where}: {exc}") from None
    except (can.CanError, OSError) as exc:
        raise LinkLostError(f"can-sonar: cannot open {where}: {exc}") from None


@dataclass
class LinkStats:
    """Counters since the bus was opened."""

    frames_sent: int = 0
    send_failures: int = 0
    frames_received: int = 0
    replies: int = 0
    foreign_frames: int = 0
    corrupt_frames: int = 0
    error_frames: int = 0
    heartbeats_missed: int = 0

    def as_dict(self) -> dict[str, int]:
        return asdict(self)


class BoardLink:
    """Frames of one board on one bus, stamped on ``clock`` as they arrive."""

    def __init__(self, bus: can.BusABC, codec: UsBoardCodec, clock: Clock, where: str) -> None:
        self.bus = bus
        self.codec = codec
        self.clock = clock
        self.where = where
        self.stats = LinkStats()

    def send(self, frame: Frame) -> bool:
        msg = can.Message(
            arbitration_id=frame.arbitration_id, data=frame.data, is_extended_id=False
        )
        try:
            self.bus.send(msg, timeout=0.05)
        except (can.CanError, OSError, ValueError) as exc:
            self.stats.send_failures += 1
            log.debug("%s: send failed: %s", self.where, exc)
            return False
        self.stats.frames_sent += 1
        return True

    def receive(self, timeout_s: float) -> tuple[Reply, float] | None:
        """The next reply of this board and its arrival stamp, or None (nothing usable came)."""
        try:
            msg = self.bus.recv(timeout=max(0.0, timeout_s))
        except ValueError as exc:
            # An adapter line that does not parse (slcan reports garbage this way).
            self.stats.corrupt_frames += 1
            log.debug("%s: unparseable frame: %s", self.where, exc)
            return None
        except (can.CanError, OSError) as exc:
            raise LinkLostError(f"can-sonar: bus {self.where} failed: {exc}") from None
        if msg is None:
            return None
        stamp = self.clock.now()
        self.stats.frames_received += 1
        if msg.is_error_frame:
            self.stats.error_frames += 1
            return None
        if msg.is_extended_id or msg.is_remote_frame or msg.is_fd:
            self.stats.foreign_frames += 1
            return None
        ident = msg.arbitration_id
        if ident == self.codec.base_id or not self.codec.owns(ident):
            self.stats.foreign_frames += 1
            return None
        try:
            reply = self.codec.decode_reply(Frame(ident, bytes(msg.data)))
        except FrameError as exc:
            self.stats.corrupt_frames += 1
            log.debug("%s: corrupt frame 0x%03X: %s", self.where, ident, exc)
            return None
        self.stats.replies += 1
        return reply, stamp

    def close(self) -> None:
        try:
            self.bus.shutdown()
        except (can.CanError, OSError) as exc:
            # The port may already be gone (that is often why we are closing).
            log.debug("%s: shutdown: %s", self.where, exc)

"""The board behind a serial-line CAN adapter (SLCAN / Lawicel ASCII) on a pseudo-terminal.

The emulator plays the adapter and the board at once: it holds the pty master and speaks SLCAN
on it, so the host opens the slave path with python-can's ``slcan`` interface exactly as it
would open ``/dev/ttyACM0`` with a CANable on a robot. This is what works across processes on
machines without socketcan.

Adapter commands answered: ``S`` (bitrate), ``s`` (BTR), ``O``/``L`` (open), ``C`` (close),
``V``/``v``/``N`` (versions, serial), ``F`` (status), ``Z`` (timestamps); ``t`` carries a
standard data frame. A host whose bitrate differs from the board's hears nothing, as on a
real bus. Anything else is refused with BEL, as adapters do.
"""

from __future__ import annotations

import contextlib
import os
import termios
import tty

from drivers.can_sonar.codec import Frame

#: SLCAN ``S`` codes -> bit/s.
SLCAN_BITRATES = {
    "0": 10_000,
    "1": 20_000,
    "2": 50_000,
    "3": 100_000,
    "4": 125_000,
    "5": 250_000,
    "6": 500_000,
    "7": 750_000,
    "8": 1_000_000,
}
_OK = b"\r"
_ERROR = b"\a"
#: Bytes waiting for a host that stopped reading are dropped beyond this (it has gone).
_MAX_PENDING = 16_384


class SlcanPty:
    """A pseudo-terminal speaking SLCAN; frames in and out as codec ``Frame`` values."""

    def __init__(self, bitrate: int) -> None:
        self.bitrate = bitrate
        self._master, self._slave = os.openpty()
        # Raw from the start: with the default echo on, the board would read its own replies
        # back before the host has opened the port and set it raw itself.
        tty.setraw(self._slave)
        os.set_blocking(self._master, False)
        self.path = os.ttyname(self._slave)
        self._rx = bytearray()
        self._tx = bytearray()
        self._open = False
        self._bitrate_ok = True
        self.bad_lines = 0
        self.overflows = 0

    def fileno(self) -> int:
        return self._master

    def receive(self) -> list[Frame]:
        """Frames the host sent since the last call (adapter commands are answered here)."""
        self._flush()
        try:
            while True:
                chunk = os.read(self._master, 4096)
                if not chunk:
                    break
                self._rx += chunk
                if len(chunk) < 4096:
                    break
        except BlockingIOError:
            pass
        except OSError:
            # EIO: no process holds the slave open any more. We keep our own slave descriptor
            # open so this is rare; either way there is nothing to read.
            return []
        frames: list[Frame] = []
        while True:
            end = self._rx.find(b"\r")
            if end < 0:
                break
            line = bytes(self._rx[:end])
            del self._rx[: end + 1]
            frame = self._line(line.strip(b"\n"))
            if frame is not None:
                frames.append(frame)
        if len(self._rx) > 64:  # no CR in sight: garbage, not a line being written
            self._rx.clear()
            self.bad_lines += 1
        return frames

    def _line(self, line: bytes) -> Frame | None:
        if not line:
            self._write(_OK)
            return None
        cmd, arg = chr(line[0]), line[1:].decode("ascii", "replace")
        if cmd == "t":
            frame = _parse_standard(arg)
            if frame is None:
                self.bad_lines += 1
                self._write(_ERROR)
                return None
            if not (self._open and self._bitrate_ok):
                return None  # a closed channel, or one at another bitrate, hears nothing
            return frame
        if cmd in "TrRdDbB":
            return None  # extended, remote and FD frames are not this board's
        if cmd == "S":
            bitrate = SLCAN_BITRATES.get(arg)
            if bitrate is None:
                self._write(_ERROR)
                return None
            self._bitrate_ok = bitrate == self.bitrate
        elif cmd in "OL":
            self._open = True
        elif cmd == "C":
            self._open = False
            # A host closing (or a new one starting, which closes first) must not read replies
            # meant for an earlier session as if they were fresh.
            termios.tcflush(self._slave, termios.TCIFLUSH)
            self._tx.clear()
        elif cmd in "Vv":
            self._write(b"V1013\r" if cmd == "V" else b"v1013\r")
            return None
        elif cmd == "N":
            self._write(b"NEMU1\r")
            return None
        elif cmd == "F":
            self._write(b"F00\r")
            return None
        elif cmd not in "sZ":
            self._write(_ERROR)
            return None
        self._write(_OK)
        return None

    def send(self, frame: Frame) -> None:
        if not (self._open and self._bitrate_ok):
            return
        data = frame.data
        self._write(f"t{frame.arbitration_id:03X}{len(data):d}{data.hex().upper()}\r".encode())

    def send_bus_error(self) -> None:
        if self._open:
            self._write(_ERROR)

    def _write(self, data: bytes) -> None:
        self._tx += data
        self._flush()

    def _flush(self) -> None:
        if not self._tx:
            return
        try:
            n = os.write(self._master, self._tx)
        except BlockingIOError:
            n = 0
        except OSError:
            self._tx.clear()
            return
        del self._tx[:n]
        if len(self._tx) > _MAX_PENDING:
            self._tx.clear()
            self.overflows += 1

    def close(self) -> None:
        for fd in (self._master, self._slave):
            with contextlib.suppress(OSError):
                os.close(fd)


def _parse_standard(arg: str) -> Frame | None:
    """``iiiL dd..``: 3 hex digits of identifier, one digit of length, 2 hex digits a byte."""
    if len(arg) < 4:
        return None
    try:
        ident = int(arg[:3], 16)
        length = int(arg[3])
        if length > 8 or len(arg) != 4 + 2 * length:
            return None
        data = bytes.fromhex(arg[4:])
    except ValueError:
        return None
    if ident > 0x7FF:
        return None
    return Frame(ident, data)

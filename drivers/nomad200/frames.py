"""Frames ``01 | LEN_lo LEN_hi | TYPE | payload | CHK | 5C`` and a resynchronising stream decoder.

LEN counts TYPE + payload + CHK; CHK is the low byte of the sum of every byte before it, start byte
included. There is no byte stuffing, so the length is the only thing that delimits a frame and a
0x01 or 0x5C inside a payload means nothing. That is why the stream decoder, after any error,
drops only the one byte it took for a start byte and looks again: a real frame may begin inside
the span a corrupt length claimed.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass

from drivers.nomad200.errors import ChecksumError, FramingError, LengthError, ProtocolError
from drivers.nomad200.integers import U16_MAX, check_range
from drivers.nomad200.opcodes import describe

START = 0x01
END = 0x5C
#: Bytes of a frame not counted by LEN: the start byte, the two length bytes and the end byte.
OVERHEAD = 4
#: A frame must carry a TYPE and a CHK. The reference only demands LEN >= 1, but a LEN of 1
#: leaves no TYPE, so no command could be meant by it.
MIN_LEN = 2
#: Default bound on LEN. The largest state reply (every sensor, every "pos" attachment, 482 laser
#: points) has LEN 2278; SPECIAL (user) packets may legally be larger, so raise it for those.
DEFAULT_MAX_LEN = 4096


def checksum(data: bytes) -> int:
    """CHK for the bytes from the start byte through the last payload byte."""
    return sum(data) & 0xFF


@dataclass(frozen=True)
class Frame:
    """One frame's meaning: its TYPE byte and the payload between TYPE and CHK."""

    opcode: int
    payload: bytes = b""

    def __post_init__(self) -> None:
        check_range(self.opcode, 0, 0xFF, "frame.opcode", "unsigned 8-bit")
        object.__setattr__(self, "payload", bytes(self.payload))
        check_range(len(self.payload), 0, U16_MAX - MIN_LEN, "len(frame.payload)", "payload size")

    @property
    def length(self) -> int:
        """The LEN field: TYPE + payload + CHK."""
        return len(self.payload) + MIN_LEN

    def encode(self) -> bytes:
        length = self.length
        body = bytes((START, length & 0xFF, length >> 8, self.opcode)) + self.payload
        return body + bytes((checksum(body), END))


def _check_length(length: int, max_len: int, where: str) -> None:
    if length < MIN_LEN:
        raise LengthError(
            f"LEN 0x{length:04X} ({length}) {where} is below the minimum {MIN_LEN} (TYPE + CHK)"
        )
    if length > max_len:
        raise LengthError(f"LEN 0x{length:04X} ({length}) {where} exceeds the maximum {max_len}")


def _frame_at(buf: bytes | bytearray, i: int, max_len: int, base: int) -> tuple[Frame, int] | None:
    """Parse the frame whose start byte is ``buf[i]``.

    Returns the frame and its size, None if more bytes are needed, or raises if the bytes cannot be
    a frame. ``base`` is the stream offset of ``buf[0]``, only for the error messages.
    """
    where = f"at byte {base + i}"
    if len(buf) - i < 3:
        return None
    length = buf[i + 1] | (buf[i + 2] << 8)
    _check_length(length, max_len, where)
    size = length + OVERHEAD
    if len(buf) - i < size:
        return None
    end = buf[i + size - 1]
    if end != END:
        raise FramingError(
            f"frame {where} with LEN {length}: expected end byte 0x{END:02X} at byte "
            f"{base + i + size - 1}, got 0x{end:02X}"
        )
    expected = checksum(buf[i : i + size - 2])
    actual = buf[i + size - 2]
    if actual != expected:
        raise ChecksumError(
            f"frame {where}, type {describe(buf[i + 3])}: checksum expected 0x{expected:02X}, "
            f"got 0x{actual:02X}",
            expected,
            actual,
        )
    return Frame(buf[i + 3], bytes(buf[i + 4 : i + size - 2])), size


def decode_frame(data: bytes, max_len: int = DEFAULT_MAX_LEN) -> Frame:
    """Decode exactly one complete frame; anything short, long or inconsistent raises."""
    if not data:
        raise FramingError("empty input: expected a frame starting with 0x01")
    if data[0] != START:
        raise FramingError(f"expected start byte 0x{START:02X}, got 0x{data[0]:02X}")
    found = _frame_at(data, 0, max_len, 0)
    if found is None:
        need = (
            f"{(data[1] | data[2] << 8) + OVERHEAD} bytes as its LEN says"
            if len(data) >= 3
            else f"at least {MIN_LEN + OVERHEAD} bytes"
        )
        raise FramingError(f"truncated frame: got {len(data)} bytes, needs {need}")
    frame, size = found
    if size != len(data):
        raise FramingError(
            f"{len(data) - size} unexpected byte(s) after a {size}-byte frame of type "
            f"{describe(frame.opcode)}"
        )
    return frame


class FrameDecoder:
    """Turns a byte stream, fed in arbitrary pieces, into frames; skips and counts what is not.

    Garbage, bad lengths, bad end bytes and bad checksums never stop decoding: the offending start
    byte (or run of non-start bytes) is dropped, counted in ``discarded``, and the error recorded in
    ``errors`` (the most recent ``keep_errors``; ``error_count`` has the total). The buffer never
    holds more than ``max_frame_size - 1`` bytes between calls.

    A frame cut short is only noticed once enough later bytes arrive to show its end byte or
    checksum is wrong; the protocol is one request, one reply, so on a reply timeout the owner
    should call ``reset()``, just as the original client flushes its input before each request.
    """

    def __init__(self, max_len: int = DEFAULT_MAX_LEN, keep_errors: int = 32) -> None:
        self.max_len = check_range(max_len, MIN_LEN, U16_MAX, "max_len", "LEN")
        self.errors: deque[ProtocolError] = deque(maxlen=keep_errors)
        self.error_count = 0
        self.discarded = 0
        self._buf = bytearray()
        self._consumed = 0  # stream offset of _buf[0], for error messages

    @property
    def max_frame_size(self) -> int:
        return self.max_len + OVERHEAD

    @property
    def pending(self) -> int:
        """Bytes held back as the start of a frame not yet complete."""
        return len(self._buf)

    def _reject(self, error: ProtocolError, count: int) -> None:
        self.errors.append(error)
        self.error_count += 1
        self.discarded += count

    def feed(self, data: bytes) -> list[Frame]:
        """Add bytes; return every frame they complete, in order."""
        buf = self._buf
        buf += data
        frames: list[Frame] = []
        i = 0
        while i < len(buf):
            if buf[i] != START:
                j = buf.find(START, i)
                j = len(buf) if j < 0 else j
                self._reject(
                    FramingError(
                        f"expected start byte 0x{START:02X} at byte {self._consumed + i}, got "
                        f"0x{buf[i]:02X}; skipped {j - i} byte(s)"
                    ),
                    j - i,
                )
                i = j
                continue
            try:
                found = _frame_at(buf, i, self.max_len, self._consumed)
            except ProtocolError as error:
                self._reject(error, 1)
                i += 1
                continue
            if found is None:
                break
            frame, size = found
            frames.append(frame)
            i += size
        del buf[:i]
        self._consumed += i
        return frames

    def reset(self) -> int:
        """Drop a partial frame (after a reply timeout); return how many bytes were dropped."""
        dropped = len(self._buf)
        if dropped:
            self._reject(
                FramingError(
                    f"truncated frame: {dropped} byte(s) from byte {self._consumed} "
                    "dropped by reset"
                ),
                dropped,
            )
            self._consumed += dropped
            self._buf.clear()
        return dropped

"""Integers as the Nomad 200 puts them on the wire: little-endian, signed ones SIGN-MAGNITUDE.

Sign-magnitude (not two's complement) means the top bit is only a sign flag: -450 is ``c2 81``
(magnitude 0x01c2, plus 0x80 in the high byte). Two consequences:

* the ranges are symmetric, -32767..32767 and -(2**31 - 1)..2**31 - 1;
* there is a "negative zero" (``00 80``). Encoders never produce it (0 is not < 0); decoders read it
  as 0, as the original client does, so decoding then re-encoding those bytes gives ``00 00``.

Encoders raise ``ValueError`` naming the field and the value when it does not fit, so an oversized
velocity fails loudly instead of wrapping into a different command.
"""

from __future__ import annotations

import operator

from drivers.nomad200.errors import PayloadError

U8_MAX = 0xFF
U16_MAX = 0xFFFF
S16_MAX = 0x7FFF
U24_MAX = 0xFF_FFFF
U32_MAX = 0xFFFF_FFFF
S32_MAX = 0x7FFF_FFFF


def check_range(value: int, low: int, high: int, field: str, kind: str) -> int:
    """Return ``value`` as an int if ``low <= value <= high``; else ValueError naming ``field``."""
    try:
        number = operator.index(value)
    except TypeError:
        raise TypeError(
            f"{field} must be an integer, got {type(value).__name__} {value!r}"
        ) from None
    if not low <= number <= high:
        raise ValueError(f"{field} = {number} is outside the {kind} range {low}..{high}")
    return number


def encode_u8(value: int, field: str) -> bytes:
    """One unsigned byte."""
    return bytes((check_range(value, 0, U8_MAX, field, "unsigned 8-bit"),))


def encode_u16(value: int, field: str) -> bytes:
    """Plain little-endian unsigned 16-bit."""
    return check_range(value, 0, U16_MAX, field, "unsigned 16-bit").to_bytes(2, "little")


def encode_s16(value: int, field: str) -> bytes:
    """Little-endian sign-magnitude 16-bit: bit 15 of the pair is the sign."""
    number = check_range(value, -S16_MAX, S16_MAX, field, "sign-magnitude 16-bit")
    magnitude = abs(number)
    return bytes((magnitude & 0xFF, (magnitude >> 8) | (0x80 if number < 0 else 0)))


def encode_u32(value: int, field: str) -> bytes:
    """Plain little-endian unsigned 32-bit (timestamps)."""
    return check_range(value, 0, U32_MAX, field, "unsigned 32-bit").to_bytes(4, "little")


def encode_s32(value: int, field: str) -> bytes:
    """Little-endian sign-magnitude 32-bit: bit 31 is the sign."""
    number = check_range(value, -S32_MAX, S32_MAX, field, "sign-magnitude 32-bit")
    word = abs(number) | (0x8000_0000 if number < 0 else 0)
    return word.to_bytes(4, "little")


def decode_u16(data: bytes) -> int:
    """Inverse of ``encode_u16`` for exactly two bytes."""
    return int.from_bytes(data, "little")


def decode_s16(data: bytes) -> int:
    """Inverse of ``encode_s16``; ``00 80`` (negative zero) reads as 0."""
    magnitude = ((data[1] & 0x7F) << 8) | data[0]
    return -magnitude if data[1] & 0x80 else magnitude


def decode_u32(data: bytes) -> int:
    """Inverse of ``encode_u32`` for exactly four bytes."""
    return int.from_bytes(data, "little")


def decode_s32(data: bytes) -> int:
    """Inverse of ``encode_s32``; ``00 00 00 80`` (negative zero) reads as 0."""
    word = int.from_bytes(data, "little")
    magnitude = word & S32_MAX
    return -magnitude if word & 0x8000_0000 else magnitude


class Reader:
    """A cursor over one payload.

    Running out of bytes, or leaving some unread, becomes a ``PayloadError`` that names the message
    and the field, where slicing by hand would give an IndexError or silently ignore the rest.
    """

    def __init__(self, data: bytes, what: str) -> None:
        self._data = bytes(data)
        self._pos = 0
        self.what = what

    @property
    def remaining(self) -> int:
        return len(self._data) - self._pos

    def take(self, size: int, field: str) -> bytes:
        if self.remaining < size:
            raise PayloadError(
                f"{self.what}: payload too short for {field}: needs {size} more byte(s) at "
                f"offset {self._pos}, only {self.remaining} left (payload is {len(self._data)})"
            )
        chunk = self._data[self._pos : self._pos + size]
        self._pos += size
        return chunk

    def u8(self, field: str) -> int:
        return self.take(1, field)[0]

    def u16(self, field: str) -> int:
        return decode_u16(self.take(2, field))

    def s16(self, field: str) -> int:
        return decode_s16(self.take(2, field))

    def u32(self, field: str) -> int:
        return decode_u32(self.take(4, field))

    def s32(self, field: str) -> int:
        return decode_s32(self.take(4, field))

    def finish(self) -> None:
        """Raise if bytes are left: a longer payload means we misread the layout."""
        if self.remaining:
            raise PayloadError(
                f"{self.what}: {self.remaining} unexpected byte(s) after the last field "
                f"(payload is {len(self._data)} bytes, layout ends at {self._pos})"
            )

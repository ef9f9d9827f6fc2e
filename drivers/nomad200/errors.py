"""Why bytes from the wire were rejected: one small tree, so callers can catch at the right depth.

``ProtocolError`` derives from ``ValueError`` because every one of these is bad input data.
Out-of-range values handed to an encoder are a caller's mistake, not a wire fault, so they raise a
plain ``ValueError`` (naming the field and the value) instead of anything in this tree.

    ProtocolError
    ├── FramingError          start or end byte wrong, frame truncated or followed by extra bytes
    │   └── LengthError       LEN field below the minimum or above the configured maximum
    ├── ChecksumError         CHK byte does not match the bytes it covers
    ├── UnknownOpcodeError    TYPE byte is not an opcode of the protocol (in that direction)
    ├── PayloadError          payload has the wrong size or a field outside its domain
    └── UnexpectedReplyError  reply TYPE neither echoes the request's opcode nor is NAK
"""

from __future__ import annotations


class ProtocolError(ValueError):
    """Base of every decoding failure."""


class FramingError(ProtocolError):
    """The frame's start byte, end byte or overall size is wrong."""


class LengthError(FramingError):
    """The LEN field is impossible (< 2) or above the bound the decoder was given."""


class ChecksumError(ProtocolError):
    """The CHK byte disagrees with the sum of the bytes before it."""

    def __init__(self, message: str, expected: int, actual: int) -> None:
        super().__init__(message)
        self.expected = expected
        self.actual = actual


class UnknownOpcodeError(ProtocolError):
    """The TYPE byte names no opcode this codec knows in this direction."""

    def __init__(self, message: str, opcode: int) -> None:
        super().__init__(message)
        self.opcode = opcode


class PayloadError(ProtocolError):
    """The frame is sound but its payload does not fit the opcode."""


class UnexpectedReplyError(ProtocolError):
    """The reply's TYPE does not echo the request's opcode (and is not NAK)."""

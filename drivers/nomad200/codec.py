"""The Nomad 200 host protocol codec: whole frames in, typed messages out, and back.

Pure: no I/O, clocks or threads, so the driver (host side) and an emulator (robot side) share it.

* host:  ``encode_request(Vm(100, -450, 0))`` ... ``decode_reply(frame, mask, request=Opcode.VM)``
* robot: ``decode_request(frame)`` ... ``encode_reply(StateReply(Opcode.VM, state), mask)``

``FrameDecoder`` cuts a byte stream into frames; these functions give the frames their meaning.
Replies need the state mask last configured with CT, because state replies are laid out by it and
the GET_* replies carry "pos" attachments when its pos bits are on. Errors are the ``ProtocolError``
tree of ``errors``; encoders raise plain ``ValueError`` for out-of-range values.
"""

from __future__ import annotations

from drivers.nomad200.commands import (
    COMMANDS,
    Ac,
    Command,
    CompassMode,
    ConfCp,
    ConfIr,
    ConfLs,
    ConfSg,
    ConfSn,
    ConfTm,
    Ct,
    Da,
    Dp,
    GetBp,
    GetCp,
    GetIr,
    GetLs,
    GetRa,
    GetRc,
    GetRv,
    GetSg,
    GetSn,
    Gs,
    Lp,
    Mv,
    MvAxis,
    MvMode,
    Nak,
    Pa,
    Pr,
    SetupLs,
    Sp,
    Special,
    St,
    Tk,
    Vm,
    Ws,
    Zr,
)
from drivers.nomad200.errors import (
    ChecksumError,
    FramingError,
    LengthError,
    PayloadError,
    ProtocolError,
    UnexpectedReplyError,
    UnknownOpcodeError,
)
from drivers.nomad200.frames import DEFAULT_MAX_LEN, Frame, FrameDecoder, decode_frame
from drivers.nomad200.opcodes import Opcode, describe
from drivers.nomad200.replies import (
    BumperReply,
    CompassCalibrationReply,
    CompassReply,
    ConfigurationReply,
    IrReply,
    NakReply,
    RawReply,
    Reply,
    SonarReply,
    StateReply,
    VelocityReply,
    reply_class,
)
from drivers.nomad200.state import PosData, State, StateLayout, StateMask

__all__ = [
    "COMMANDS",
    "DEFAULT_MAX_LEN",
    "Ac",
    "BumperReply",
    "ChecksumError",
    "Command",
    "CompassCalibrationReply",
    "CompassMode",
    "CompassReply",
    "ConfCp",
    "ConfIr",
    "ConfLs",
    "ConfSg",
    "ConfSn",
    "ConfTm",
    "ConfigurationReply",
    "Ct",
    "Da",
    "Dp",
    "Frame",
    "FrameDecoder",
    "FramingError",
    "GetBp",
    "GetCp",
    "GetIr",
    "GetLs",
    "GetRa",
    "GetRc",
    "GetRv",
    "GetSg",
    "GetSn",
    "Gs",
    "IrReply",
    "LengthError",
    "Lp",
    "Mv",
    "MvAxis",
    "MvMode",
    "Nak",
    "NakReply",
    "Opcode",
    "Pa",
    "PayloadError",
    "PosData",
    "Pr",
    "ProtocolError",
    "RawReply",
    "Reply",
    "SetupLs",
    "SonarReply",
    "Sp",
    "Special",
    "St",
    "State",
    "StateLayout",
    "StateMask",
    "StateReply",
    "Tk",
    "UnexpectedReplyError",
    "UnknownOpcodeError",
    "VelocityReply",
    "Vm",
    "Ws",
    "Zr",
    "decode_frame",
    "decode_reply",
    "decode_request",
    "encode_reply",
    "encode_request",
]


def _frame(data: bytes | Frame, max_len: int) -> Frame:
    return data if isinstance(data, Frame) else decode_frame(data, max_len)


def encode_request(command: Command) -> bytes:
    """The frame for a host-to-robot request."""
    return command.encode()


def decode_request(data: bytes | Frame, max_len: int = DEFAULT_MAX_LEN) -> Command:
    """The request in one frame (bytes of exactly one frame, or a ``Frame`` already cut)."""
    frame = _frame(data, max_len)
    try:
        cls = COMMANDS[Opcode(frame.opcode)]
    except ValueError:
        raise UnknownOpcodeError(
            f"unknown request opcode {describe(frame.opcode)}", frame.opcode
        ) from None
    return cls.from_payload(frame.payload)


def encode_reply(reply: Reply, mask: StateMask) -> bytes:
    """The frame for a robot-to-host reply, laid out for ``mask``."""
    return reply.encode(mask)


def decode_reply(
    data: bytes | Frame,
    mask: StateMask,
    request: int | None = None,
    max_len: int = DEFAULT_MAX_LEN,
) -> Reply:
    """The reply in one frame, read with the state mask the robot was last configured with.

    With ``request`` (the opcode just sent), a reply that neither echoes it nor is NAK raises
    ``UnexpectedReplyError``: it answers some earlier request and must not be taken for this one.
    """
    frame = _frame(data, max_len)
    if request is not None and frame.opcode not in (request, Opcode.NAK):
        raise UnexpectedReplyError(
            f"expected a reply to {describe(request)} (or NAK), got type {describe(frame.opcode)}"
        )
    cls = reply_class(frame.opcode, len(frame.payload))
    return cls.from_payload(Opcode(frame.opcode), frame.payload, mask)

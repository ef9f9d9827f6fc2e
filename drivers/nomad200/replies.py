"""Robot-to-host replies. A reply's TYPE echoes the request's opcode; NAK may come instead.

Most requests are answered with the state reply (``StateReply``), laid out by the state mask. The
GET_* requests have replies of their own; those for IR, sonar, bumper and compass also carry "pos"
attachments when the mask's matching pos bit is on, so every decoder here takes the mask.

Settled from the original client where the reference is silent: GET_IR answers with all 16 IR
nibbles (8 bytes) then the time; GET_RC and GET_RV carry no time; CONF_CP is answered with three
compass-calibration score bytes (the reference lumps it with the state replies, so a payload that is
not exactly 3 bytes is read as state); GET_RA, GET_LS, GET_SG and SPECIAL replies stay opaque.
Values are checked when a reply is encoded, against the mask it is encoded for.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar, Self

from drivers.nomad200.errors import UnknownOpcodeError
from drivers.nomad200.frames import Frame
from drivers.nomad200.integers import (
    U16_MAX,
    Reader,
    check_range,
    encode_s16,
    encode_u8,
    encode_u16,
    encode_u32,
)
from drivers.nomad200.opcodes import STATE_REPLY_OPCODES, Opcode, describe
from drivers.nomad200.state import (
    IR_MAX,
    SENSORS,
    PosData,
    State,
    StateLayout,
    StateMask,
    encode_bumper,
    read_bumper,
)

#: Payload size of the CONF_CP calibration reply; no state reply is this short (its tail is 7).
CALIBRATION_SIZE = 3


class Reply:
    """A reply. Subclasses are frozen dataclasses with an ``opcode`` and the two methods."""

    opcode: Opcode

    def payload(self, mask: StateMask) -> bytes:
        raise NotImplementedError

    @classmethod
    def from_payload(cls, opcode: Opcode, payload: bytes, mask: StateMask) -> Self:
        raise NotImplementedError

    def to_frame(self, mask: StateMask) -> Frame:
        return Frame(self.opcode, self.payload(mask))

    def encode(self, mask: StateMask) -> bytes:
        """The complete frame, laid out for ``mask`` (the one the host configured with CT)."""
        return self.to_frame(mask).encode()


@dataclass(frozen=True)
class StateReply(Reply):
    """The answer to motion, configuration and GS requests: what the mask selects, plus the tail."""

    opcode: Opcode
    state: State

    def __post_init__(self) -> None:
        if self.opcode not in STATE_REPLY_OPCODES:
            raise ValueError(f"state reply opcode {describe(self.opcode)} is not answered by state")
        object.__setattr__(self, "opcode", Opcode(self.opcode))

    def payload(self, mask: StateMask) -> bytes:
        return StateLayout(mask).encode(self.state)

    @classmethod
    def from_payload(cls, opcode: Opcode, payload: bytes, mask: StateMask) -> Self:
        what = f"state reply to {describe(opcode)}"
        return cls(opcode, StateLayout(mask).decode(payload, what))


@dataclass(frozen=True)
class NakReply(Reply):
    """The robot refused or did not understand the request. The original client never retries."""

    opcode: ClassVar[Opcode] = Opcode.NAK

    def payload(self, mask: StateMask) -> bytes:
        return b""

    @classmethod
    def from_payload(cls, opcode: Opcode, payload: bytes, mask: StateMask) -> Self:
        Reader(payload, "nak").finish()
        return cls()


def _check_pos(pos: object, wanted: bool, what: str, bit: str) -> None:
    if (pos is not None) != wanted:
        problem, state = ("missing", "on") if wanted else ("given", "off")
        raise ValueError(f"{what}.pos is {problem} but mask.{bit} is {state}")


def _sixteen(values: tuple[object, ...], name: str) -> None:
    if len(values) != SENSORS:
        raise ValueError(f"{name} must have {SENSORS} entries, got {len(values)}")


@dataclass(frozen=True)
class _SensorRing(Reply):
    """16 readings, then one "pos" per sensor if the mask's pos bit is on, then the time (ms)."""

    readings: tuple[int, ...]
    pos: tuple[PosData, ...] | None = None
    time_ms: int = 0

    POS_BIT: ClassVar[str]

    def __post_init__(self) -> None:
        object.__setattr__(self, "readings", tuple(self.readings))
        if self.pos is not None:
            object.__setattr__(self, "pos", tuple(self.pos))

    @classmethod
    def _name(cls) -> str:
        return cls.opcode.name.lower()

    def _encode_readings(self) -> bytes:
        raise NotImplementedError

    @classmethod
    def _read_readings(cls, reader: Reader) -> tuple[int, ...]:
        raise NotImplementedError

    def payload(self, mask: StateMask) -> bytes:
        name = self._name()
        _sixteen(self.readings, f"{name}.readings")
        _check_pos(self.pos, getattr(mask, self.POS_BIT), name, self.POS_BIT)
        out = self._encode_readings()
        if self.pos is not None:
            _sixteen(self.pos, f"{name}.pos")
            out += b"".join(p.encode(f"{name}.pos[{k}]") for k, p in enumerate(self.pos))
        return out + encode_u32(self.time_ms, f"{name}.time_ms")

    @classmethod
    def from_payload(cls, opcode: Opcode, payload: bytes, mask: StateMask) -> Self:
        name = cls._name()
        reader = Reader(payload, name)
        readings = cls._read_readings(reader)
        pos = None
        if getattr(mask, cls.POS_BIT):
            pos = tuple(PosData.read(reader, f"{name}.pos[{k}]") for k in range(SENSORS))
        time_ms = reader.u32(f"{name}.time_ms")
        reader.finish()
        return cls(readings, pos, time_ms)


@dataclass(frozen=True)
class IrReply(_SensorRing):
    """All 16 IR readings (0-15, two per byte, low nibble first)."""

    opcode: ClassVar[Opcode] = Opcode.GET_IR
    POS_BIT = "pos_ir"

    def _encode_readings(self) -> bytes:
        for k, value in enumerate(self.readings):
            check_range(value, 0, IR_MAX, f"get_ir.readings[{k}]", "IR")
        pairs = zip(self.readings[::2], self.readings[1::2], strict=True)
        return bytes(lo | hi << 4 for lo, hi in pairs)

    @classmethod
    def _read_readings(cls, reader: Reader) -> tuple[int, ...]:
        packed = reader.take(SENSORS // 2, "get_ir.readings")
        return tuple(v for byte in packed for v in (byte & 0x0F, byte >> 4))


@dataclass(frozen=True)
class SonarReply(_SensorRing):
    """All 16 sonar ranges in whole inches, from the sonar skin."""

    opcode: ClassVar[Opcode] = Opcode.GET_SN
    POS_BIT = "pos_sonar"

    def _encode_readings(self) -> bytes:
        return b"".join(encode_u8(v, f"get_sn.readings[{k}]") for k, v in enumerate(self.readings))

    @classmethod
    def _read_readings(cls, reader: Reader) -> tuple[int, ...]:
        return tuple(reader.take(SENSORS, "get_sn.readings"))


@dataclass(frozen=True)
class _Signed(Reply):
    """A fixed list of sign-magnitude 16-bit values, no time."""

    FIELDS: ClassVar[tuple[str, ...]]

    def payload(self, mask: StateMask) -> bytes:
        name = self.opcode.name.lower()
        return b"".join(encode_s16(getattr(self, f), f"{name}.{f}") for f in self.FIELDS)

    @classmethod
    def from_payload(cls, opcode: Opcode, payload: bytes, mask: StateMask) -> Self:
        name = cls.opcode.name.lower()
        reader = Reader(payload, name)
        values = {f: reader.s16(f"{name}.{f}") for f in cls.FIELDS}
        reader.finish()
        return cls(**values)


@dataclass(frozen=True)
class ConfigurationReply(_Signed):
    """x, y in 1/10 inch; steering and turret angles in 1/10 degree."""

    x: int
    y: int
    steer: int
    turret: int

    opcode: ClassVar[Opcode] = Opcode.GET_RC
    FIELDS = ("x", "y", "steer", "turret")


@dataclass(frozen=True)
class VelocityReply(_Signed):
    """Translation velocity in 1/10 inch/s; steering and turret in 1/10 degree/s."""

    trans: int
    steer: int
    turret: int

    opcode: ClassVar[Opcode] = Opcode.GET_RV
    FIELDS = ("trans", "steer", "turret")


@dataclass(frozen=True)
class _OneSensor(Reply):
    """One value, then the "pos" if the mask's pos bit is on, then the time (ms)."""

    value: int
    pos: PosData | None = None
    time_ms: int = 0

    POS_BIT: ClassVar[str]

    def _encode_value(self) -> bytes:
        raise NotImplementedError

    @classmethod
    def _read_value(cls, reader: Reader) -> int:
        raise NotImplementedError

    def payload(self, mask: StateMask) -> bytes:
        name = self.opcode.name.lower()
        _check_pos(self.pos, getattr(mask, self.POS_BIT), name, self.POS_BIT)
        out = self._encode_value()
        if self.pos is not None:
            out += self.pos.encode(f"{name}.pos")
        return out + encode_u32(self.time_ms, f"{name}.time_ms")

    @classmethod
    def from_payload(cls, opcode: Opcode, payload: bytes, mask: StateMask) -> Self:
        name = cls.opcode.name.lower()
        reader = Reader(payload, name)
        value = cls._read_value(reader)
        pos = PosData.read(reader, f"{name}.pos") if getattr(mask, cls.POS_BIT) else None
        time_ms = reader.u32(f"{name}.time_ms")
        reader.finish()
        return cls(value, pos, time_ms)


@dataclass(frozen=True)
class CompassReply(_OneSensor):
    """Compass heading (``value``, unsigned 16-bit)."""

    opcode: ClassVar[Opcode] = Opcode.GET_CP
    POS_BIT = "pos_compass"

    def _encode_value(self) -> bytes:
        return encode_u16(self.value, "get_cp.value")

    @classmethod
    def _read_value(cls, reader: Reader) -> int:
        return reader.u16("get_cp.value")


@dataclass(frozen=True)
class BumperReply(_OneSensor):
    """The 24 bumper bits as one number (``value``); the wire sends its bytes reversed."""

    opcode: ClassVar[Opcode] = Opcode.GET_BP
    POS_BIT = "pos_bumper"

    def _encode_value(self) -> bytes:
        return encode_bumper(self.value, "get_bp.value")

    @classmethod
    def _read_value(cls, reader: Reader) -> int:
        return read_bumper(reader, "get_bp.value")


@dataclass(frozen=True)
class CompassCalibrationReply(Reply):
    """Calibration scores for the x, y and z passes, answering CONF_CP."""

    x: int
    y: int
    z: int

    opcode: ClassVar[Opcode] = Opcode.CONF_CP

    def payload(self, mask: StateMask) -> bytes:
        return b"".join(encode_u8(getattr(self, a), f"conf_cp.{a}") for a in ("x", "y", "z"))

    @classmethod
    def from_payload(cls, opcode: Opcode, payload: bytes, mask: StateMask) -> Self:
        reader = Reader(payload, "conf_cp calibration")
        values = {a: reader.u8(f"conf_cp.{a}") for a in ("x", "y", "z")}
        reader.finish()
        return cls(**values)


#: Replies whose payload the reference does not describe.
RAW_REPLY_OPCODES = frozenset({Opcode.GET_RA, Opcode.GET_LS, Opcode.GET_SG, Opcode.SPECIAL})


@dataclass(frozen=True)
class RawReply(Reply):
    """A reply kept as bytes: GET_RA, GET_LS, GET_SG and SPECIAL."""

    opcode: Opcode
    data: bytes = b""

    def __post_init__(self) -> None:
        if self.opcode not in RAW_REPLY_OPCODES:
            raise ValueError(f"raw reply opcode {describe(self.opcode)} has a typed reply")
        object.__setattr__(self, "opcode", Opcode(self.opcode))
        object.__setattr__(self, "data", bytes(self.data))
        check_range(len(self.data), 0, U16_MAX - 2, "len(raw reply data)", "payload size")

    def payload(self, mask: StateMask) -> bytes:
        return self.data

    @classmethod
    def from_payload(cls, opcode: Opcode, payload: bytes, mask: StateMask) -> Self:
        return cls(opcode, payload)


_TYPED: dict[Opcode, type[Reply]] = {
    cls.opcode: cls
    for cls in (
        NakReply,
        IrReply,
        SonarReply,
        ConfigurationReply,
        VelocityReply,
        CompassReply,
        BumperReply,
    )
}


def reply_class(opcode: int, payload_size: int) -> type[Reply]:
    """The reply class for a reply frame's TYPE (the size only settles CONF_CP)."""
    try:
        op = Opcode(opcode)
    except ValueError:
        raise UnknownOpcodeError(f"unknown reply opcode {describe(opcode)}", opcode) from None
    if op == Opcode.CONF_CP and payload_size == CALIBRATION_SIZE:
        return CompassCalibrationReply
    if op in STATE_REPLY_OPCODES:
        return StateReply
    if op in RAW_REPLY_OPCODES:
        return RawReply
    return _TYPED[op]

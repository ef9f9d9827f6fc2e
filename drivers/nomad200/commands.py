"""Host-to-robot requests, one frozen dataclass per opcode, each encoding and decoding itself.

Both directions matter: the driver encodes these, a robot-side emulator decodes them. Values are
checked when a command is built, so an out-of-range one cannot exist, and decoding re-uses the same
checks (reporting them as ``PayloadError``). Units are the protocol's: 1/10 inch, 1/10 degree, per
second and per second squared, whole seconds for timeouts.

Opcodes whose payload the reference does not give (CONF_LS, GET_LS, SETUP_LS, CONF_SG, GET_SG,
SPECIAL) carry their payload as opaque ``data`` bytes, so they still travel intact.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import IntEnum
from typing import TYPE_CHECKING, Any, ClassVar, Self

from drivers.nomad200.errors import PayloadError
from drivers.nomad200.frames import Frame
from drivers.nomad200.integers import (
    S16_MAX,
    U16_MAX,
    Reader,
    check_range,
    encode_s16,
    encode_u8,
    encode_u16,
)
from drivers.nomad200.opcodes import Opcode
from drivers.nomad200.state import SENSORS, StateMask

#: Ends a firing-order list shorter than 16 entries.
ORDER_END = 0xFF
#: Text that fits a frame: LEN = TYPE + text + NUL + CHK.
TK_MAX_TEXT = U16_MAX - 3


def _build(cls: type[Any], what: str, **values: Any) -> Any:
    """Construct a decoded message; a value the constructor rejects is a fault of the payload."""
    try:
        return cls(**values)
    except PayloadError:
        raise
    except (ValueError, TypeError) as error:
        raise PayloadError(f"{what}: {error}") from error


class Command:
    """A request. Subclasses are frozen dataclasses that define ``OPCODE`` and the two methods."""

    OPCODE: ClassVar[Opcode]

    def __post_init__(self) -> None:
        self.payload()  # encoding checks every field; fail at construction, not at send time

    @classmethod
    def name(cls) -> str:
        return cls.OPCODE.name.lower()

    def payload(self) -> bytes:
        raise NotImplementedError

    @classmethod
    def from_payload(cls, payload: bytes) -> Self:
        raise NotImplementedError

    def to_frame(self) -> Frame:
        return Frame(self.OPCODE, self.payload())

    def encode(self) -> bytes:
        """The complete frame, ready for the wire."""
        return self.to_frame().encode()


# --- no payload -------------------------------------------------------------------------------


@dataclass(frozen=True)
class _Empty(Command):
    def payload(self) -> bytes:
        return b""

    @classmethod
    def from_payload(cls, payload: bytes) -> Self:
        Reader(payload, cls.name()).finish()
        return cls()


@dataclass(frozen=True)
class Gs(_Empty):
    """Get state: the reply carries what the state mask selects."""

    OPCODE = Opcode.GS


@dataclass(frozen=True)
class Nak(_Empty):
    """Negative acknowledgement (the robot sends it back instead of a reply; see ``NakReply``)."""

    OPCODE = Opcode.NAK


@dataclass(frozen=True)
class St(_Empty):
    """Stop: the robot holds its current position."""

    OPCODE = Opcode.ST


@dataclass(frozen=True)
class Lp(_Empty):
    """Limp: motors off, the robot may not hold its position."""

    OPCODE = Opcode.LP


@dataclass(frozen=True)
class Zr(_Empty):
    """Zero the robot: align steering and turret, zero position and angles (up to 120 s)."""

    OPCODE = Opcode.ZR


@dataclass(frozen=True)
class GetIr(_Empty):
    OPCODE = Opcode.GET_IR


@dataclass(frozen=True)
class GetSn(_Empty):
    OPCODE = Opcode.GET_SN


@dataclass(frozen=True)
class GetRc(_Empty):
    OPCODE = Opcode.GET_RC


@dataclass(frozen=True)
class GetRv(_Empty):
    OPCODE = Opcode.GET_RV


@dataclass(frozen=True)
class GetRa(_Empty):
    OPCODE = Opcode.GET_RA


@dataclass(frozen=True)
class GetCp(_Empty):
    OPCODE = Opcode.GET_CP


@dataclass(frozen=True)
class GetBp(_Empty):
    OPCODE = Opcode.GET_BP


# --- payloads the reference leaves unspecified -----------------------------------------------


@dataclass(frozen=True)
class _Opaque(Command):
    data: bytes = b""

    def __post_init__(self) -> None:
        object.__setattr__(self, "data", bytes(self.data))
        check_range(len(self.data), 0, U16_MAX - 2, f"len({self.name()}.data)", "payload size")

    def payload(self) -> bytes:
        return self.data

    @classmethod
    def from_payload(cls, payload: bytes) -> Self:
        return cls(payload)


@dataclass(frozen=True)
class ConfLs(_Opaque):
    """Configure the laser sensor (payload opaque)."""

    OPCODE = Opcode.CONF_LS


@dataclass(frozen=True)
class GetLs(_Opaque):
    """Get laser points (payload opaque, normally empty)."""

    OPCODE = Opcode.GET_LS


@dataclass(frozen=True)
class SetupLs(_Opaque):
    """Set up the laser (payload opaque)."""

    OPCODE = Opcode.SETUP_LS


@dataclass(frozen=True)
class ConfSg(_Opaque):
    """Configure laser line segmentation (payload opaque)."""

    OPCODE = Opcode.CONF_SG


@dataclass(frozen=True)
class GetSg(_Opaque):
    """Get laser line segments (payload opaque, normally empty)."""

    OPCODE = Opcode.GET_SG


@dataclass(frozen=True)
class Special(_Opaque):
    """A user-defined packet for on-board user code."""

    OPCODE = Opcode.SPECIAL


# --- three axes -------------------------------------------------------------------------------

_AXES = ("trans", "steer", "turret")


@dataclass(frozen=True)
class _Axes(Command):
    """Translation, steering, turret: 1/10 inch (per s, per s^2) and 1/10 degree (likewise)."""

    trans: int
    steer: int
    turret: int

    SIGNED: ClassVar[bool] = True

    def payload(self) -> bytes:
        encode = encode_s16 if self.SIGNED else encode_u16
        return b"".join(encode(getattr(self, a), f"{self.name()}.{a}") for a in _AXES)

    @classmethod
    def from_payload(cls, payload: bytes) -> Self:
        reader = Reader(payload, cls.name())
        read = reader.s16 if cls.SIGNED else reader.u16
        values = {a: read(f"{cls.name()}.{a}") for a in _AXES}
        reader.finish()
        return _build(cls, cls.name(), **values)


@dataclass(frozen=True)
class Ac(_Axes):
    """Accelerations (unsigned)."""

    OPCODE = Opcode.AC
    SIGNED = False


@dataclass(frozen=True)
class Sp(_Axes):
    """Maximum speeds for PR and PA (unsigned)."""

    OPCODE = Opcode.SP
    SIGNED = False


@dataclass(frozen=True)
class Pr(_Axes):
    """Move each axis by a relative distance at the SP speeds."""

    OPCODE = Opcode.PR


@dataclass(frozen=True)
class Pa(_Axes):
    """Move each axis to an absolute position at the SP speeds."""

    OPCODE = Opcode.PA


@dataclass(frozen=True)
class Vm(_Axes):
    """Velocity mode: move at these velocities until another command or the motion timeout."""

    OPCODE = Opcode.VM


# --- two signed values ------------------------------------------------------------------------


@dataclass(frozen=True)
class _Pair(Command):
    FIELDS: ClassVar[tuple[str, str]]

    def payload(self) -> bytes:
        return b"".join(encode_s16(getattr(self, f), f"{self.name()}.{f}") for f in self.FIELDS)

    @classmethod
    def from_payload(cls, payload: bytes) -> Self:
        reader = Reader(payload, cls.name())
        values = {f: reader.s16(f"{cls.name()}.{f}") for f in cls.FIELDS}
        reader.finish()
        return _build(cls, cls.name(), **values)


@dataclass(frozen=True)
class Dp(_Pair):
    """Define the current position as (x, y), in 1/10 inch."""

    x: int
    y: int

    OPCODE = Opcode.DP
    FIELDS = ("x", "y")


@dataclass(frozen=True)
class Da(_Pair):
    """Define the current steering and turret angles, in 1/10 degree."""

    steer: int
    turret: int

    OPCODE = Opcode.DA
    FIELDS = ("steer", "turret")


# --- configuration ----------------------------------------------------------------------------


@dataclass(frozen=True)
class Ct(Command):
    """Configure the state mask; every later state reply (this one's too) follows it."""

    mask: StateMask

    OPCODE = Opcode.CT

    def payload(self) -> bytes:
        return self.mask.to_bytes()

    @classmethod
    def from_payload(cls, payload: bytes) -> Self:
        return cls(StateMask.from_bytes(payload))


def _encode_order(order: tuple[int, ...], name: str) -> bytes:
    if len(order) > SENSORS:
        raise ValueError(f"{name} has {len(order)} entries, at most {SENSORS} fit")
    for k, sensor in enumerate(order):
        check_range(sensor, 0, SENSORS - 1, f"{name}[{k}]", "sensor index")
    return bytes(order) + bytes([ORDER_END] * (SENSORS - len(order)))


def _decode_order(data: bytes, name: str) -> tuple[int, ...]:
    # The robot reads up to the first 255; whatever follows it is left-over and ignored.
    end = data.find(ORDER_END)
    order = data if end < 0 else data[:end]
    for k, sensor in enumerate(order):
        if sensor >= SENSORS:
            raise PayloadError(
                f"{name}[{k}] = {sensor} is neither a sensor index 0..{SENSORS - 1} nor the "
                f"end marker {ORDER_END}"
            )
    return tuple(order)


@dataclass(frozen=True)
class _Firing(Command):
    """A rate-or-history byte then a firing order of up to 16 sensors (255 ends a shorter one)."""

    FIRST: ClassVar[str]
    if TYPE_CHECKING:  # a field of each subclass, declared there to come after FIRST
        order: tuple[int, ...]

    def __post_init__(self) -> None:
        object.__setattr__(self, "order", tuple(self.order))
        super().__post_init__()

    def payload(self) -> bytes:
        first = encode_u8(getattr(self, self.FIRST), f"{self.name()}.{self.FIRST}")
        return first + _encode_order(self.order, f"{self.name()}.order")

    @classmethod
    def from_payload(cls, payload: bytes) -> Self:
        reader = Reader(payload, cls.name())
        first = reader.u8(f"{cls.name()}.{cls.FIRST}")
        order = _decode_order(reader.take(SENSORS, f"{cls.name()}.order"), f"{cls.name()}.order")
        reader.finish()
        return _build(cls, cls.name(), **{cls.FIRST: first, "order": order})


@dataclass(frozen=True)
class ConfIr(_Firing):
    """Configure the infrareds: history (how much a reading depends on the last) and order."""

    history: int
    order: tuple[int, ...]

    OPCODE = Opcode.CONF_IR
    FIRST = "history"


@dataclass(frozen=True)
class ConfSn(_Firing):
    """Configure the sonars: ``rate`` in 4 ms units per sensor; rate 0 or an empty order stops."""

    rate: int
    order: tuple[int, ...]

    OPCODE = Opcode.CONF_SN
    FIRST = "rate"


class CompassMode(IntEnum):
    OFF = 0
    ON = 1
    CALIBRATE = 2


def _enum(enum: type[IntEnum], value: int, name: str) -> IntEnum:
    try:
        return enum(value)
    except ValueError:
        allowed = ", ".join(f"{m.value} {m.name}" for m in enum)
        raise ValueError(f"{name} = {value!r} is not one of {allowed}") from None


@dataclass(frozen=True)
class ConfCp(Command):
    """Configure the compass: off, on, or calibrate (the robot turns a full circle)."""

    mode: CompassMode

    OPCODE = Opcode.CONF_CP

    def __post_init__(self) -> None:
        object.__setattr__(self, "mode", _enum(CompassMode, self.mode, "conf_cp.mode"))
        super().__post_init__()

    def payload(self) -> bytes:
        return encode_u8(self.mode, "conf_cp.mode")

    @classmethod
    def from_payload(cls, payload: bytes) -> Self:
        reader = Reader(payload, cls.name())
        mode = reader.u8("conf_cp.mode")
        reader.finish()
        return _build(cls, cls.name(), mode=mode)


@dataclass(frozen=True)
class ConfTm(Command):
    """Motion timeout in seconds: motion stops if no command arrives for that long; 0 = never."""

    timeout: int

    OPCODE = Opcode.CONF_TM

    def payload(self) -> bytes:
        return encode_u8(self.timeout, "conf_tm.timeout")

    @classmethod
    def from_payload(cls, payload: bytes) -> Self:
        reader = Reader(payload, cls.name())
        timeout = reader.u8("conf_tm.timeout")
        reader.finish()
        return cls(timeout)


@dataclass(frozen=True)
class Tk(Command):
    """Speak ASCII ``text`` on the speech synthesiser (sent NUL-terminated)."""

    text: str

    OPCODE = Opcode.TK

    def payload(self) -> bytes:
        if not isinstance(self.text, str):
            raise TypeError(f"tk.text must be a str, got {type(self.text).__name__}")
        if "\0" in self.text:
            raise ValueError(f"tk.text contains a NUL at index {self.text.index(chr(0))}")
        check_range(len(self.text), 0, TK_MAX_TEXT, "len(tk.text)", "text length")
        try:
            return self.text.encode("ascii") + b"\0"
        except UnicodeEncodeError as error:
            raise ValueError(
                f"tk.text has non-ASCII {self.text[error.start]!r} at index {error.start}"
            ) from None

    @classmethod
    def from_payload(cls, payload: bytes) -> Self:
        if not payload.endswith(b"\0"):
            raise PayloadError(
                f"tk: text must end with NUL (0x00), last byte is "
                f"{f'0x{payload[-1]:02X}' if payload else 'missing (empty payload)'}"
            )
        try:
            text = payload[:-1].decode("ascii")
        except UnicodeDecodeError as error:
            raise PayloadError(
                f"tk: byte 0x{payload[error.start]:02X} at offset {error.start} is not ASCII"
            ) from None
        return _build(cls, cls.name(), text=text)


@dataclass(frozen=True)
class Ws(Command):
    """Wait until the selected axes stop, or ``timeout`` seconds pass."""

    trans: bool
    steer: bool
    turret: bool
    timeout: int

    OPCODE = Opcode.WS

    def payload(self) -> bytes:
        flags = []
        for axis in _AXES:
            flag = getattr(self, axis)
            if flag not in (0, 1):  # True and False included
                raise ValueError(f"ws.{axis} = {flag!r} must be a bool")
            flags.append(int(flag))
        return bytes(flags) + encode_u8(self.timeout, "ws.timeout")

    @classmethod
    def from_payload(cls, payload: bytes) -> Self:
        reader = Reader(payload, cls.name())
        flags = {}
        for axis in _AXES:
            flag = reader.u8(f"ws.{axis}")
            if flag > 1:
                raise PayloadError(f"ws.{axis} flag must be 0 or 1, got 0x{flag:02X}")
            flags[axis] = bool(flag)
        timeout = reader.u8("ws.timeout")
        reader.finish()
        return cls(timeout=timeout, **flags)


class MvMode(IntEnum):
    """What an MV axis value means."""

    IGNORE = 0
    VM = 1
    PR = 2
    LP = 3
    AC = 4
    SP = 5
    PA = 6
    TQ = 7
    MT = 8


@dataclass(frozen=True)
class MvAxis:
    """One axis of an MV: a mode and a signed value whose unit the mode decides."""

    mode: MvMode = MvMode.IGNORE
    value: int = 0

    def __post_init__(self) -> None:
        object.__setattr__(self, "mode", _enum(MvMode, self.mode, "mv axis mode"))
        check_range(self.value, -S16_MAX, S16_MAX, "mv axis value", "sign-magnitude 16-bit")


@dataclass(frozen=True)
class Mv(Command):
    """Mixed move: a separate mode and value for translation, steering and turret."""

    trans: MvAxis = MvAxis()
    steer: MvAxis = MvAxis()
    turret: MvAxis = MvAxis()

    OPCODE = Opcode.MV

    def payload(self) -> bytes:
        out = b""
        for axis in _AXES:
            spec = getattr(self, axis)
            if not isinstance(spec, MvAxis):
                raise TypeError(f"mv.{axis} must be an MvAxis, got {type(spec).__name__}")
            out += encode_u16(spec.mode, f"mv.{axis}.mode") + encode_s16(
                spec.value, f"mv.{axis}.value"
            )
        return out

    @classmethod
    def from_payload(cls, payload: bytes) -> Self:
        reader = Reader(payload, cls.name())
        axes = {}
        for axis in _AXES:
            mode = reader.u16(f"mv.{axis}.mode")
            value = reader.s16(f"mv.{axis}.value")
            axes[axis] = _build(MvAxis, f"mv.{axis}", mode=mode, value=value)
        reader.finish()
        return cls(**axes)


#: Every request class by its opcode.
COMMANDS: dict[Opcode, type[Command]] = {
    cls.OPCODE: cls
    for cls in (
        Ac, Sp, Pr, Pa, Vm, Ct, Gs, Nak, St, Lp, Tk, Dp, Zr, ConfIr, ConfSn, ConfCp, ConfLs,
        ConfTm, GetIr, GetSn, GetRc, GetRv, GetRa, GetCp, GetLs, SetupLs, GetBp, ConfSg, GetSg,
        Da, Ws, Mv, Special,
    )
}  # fmt: skip

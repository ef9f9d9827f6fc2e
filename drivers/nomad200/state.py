"""The state mask (set with CT) and the state reply it lays out.

A state reply carries only the fields whose mask bits are on, in a fixed order, with no tags, so
it can only be read with the mask that was configured. ``StateLayout`` turns a mask into one list
of segments used both to decode (the driver) and to encode (an emulator), so the two directions
cannot drift apart. After a CT, the reply to that CT is already laid out by the new mask.

Facts the reference leaves open, settled from the original client's behaviour:

* a "pos" attachment follows *each* selected IR sensor / sonar (so one per selected sensor, in
  index order, after all the readings), and the bumper, compass and laser ones only when that
  sensor itself is selected;
* IR readings of the selected sensors are packed in index order, two per byte, low nibble first;
  an odd count leaves the last high nibble as padding (written 0, ignored when read);
* laser data is the point mode: a count then that many unsigned 16-bit values, then its "pos";
* the compass is unsigned 16-bit; timestamps (the clock and the two in each "pos") are unsigned
  32-bit, the other "pos" values sign-magnitude 32-bit.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import dataclass, fields
from typing import Any

from drivers.nomad200.errors import PayloadError
from drivers.nomad200.integers import (
    U24_MAX,
    Reader,
    check_range,
    encode_s16,
    encode_s32,
    encode_u8,
    encode_u16,
    encode_u32,
)

SENSORS = 16
MASK_SIZE = 7
POS_SIZE = 36
IR_MAX = 0x0F
NO_READING: tuple[None, ...] = (None,) * SENSORS
_PER_SENSOR = ("ir", "ir_pos", "sonar", "sonar_pos")

# Byte 4 of the mask, bit by bit (mask indices 33-40). The original client puts index 30 (a sonar)
# in bit 7 by mistake; this codec writes the turret velocity there, which is what the robot reads.
_BYTE4 = ("bumper", "x", "y", "steer", "turret", "vel_trans", "vel_steer", "vel_turret")
# Byte 6, bit 0 is the compass; bits 1-5 are the "pos" attachments (mask index 0).
_BYTE6 = ("compass", "pos_ir", "pos_sonar", "pos_bumper", "pos_laser", "pos_compass")


def _sensor_set(value: Iterable[int], name: str) -> frozenset[int]:
    members = frozenset(value)
    for index in members:
        check_range(index, 0, SENSORS - 1, f"{name} sensor index", "sensor")
    return members


@dataclass(frozen=True)
class StateMask:
    """Which fields a state reply carries. ``ir`` and ``sonar`` are sets of sensor indices 0-15."""

    ir: frozenset[int] = frozenset()
    sonar: frozenset[int] = frozenset()
    bumper: bool = False
    x: bool = False
    y: bool = False
    steer: bool = False
    turret: bool = False
    vel_trans: bool = False
    vel_steer: bool = False
    vel_turret: bool = False
    laser: bool = False
    compass: bool = False
    pos_ir: bool = False
    pos_sonar: bool = False
    pos_bumper: bool = False
    pos_laser: bool = False
    pos_compass: bool = False

    def __post_init__(self) -> None:
        object.__setattr__(self, "ir", _sensor_set(self.ir, "mask.ir"))
        object.__setattr__(self, "sonar", _sensor_set(self.sonar, "mask.sonar"))

    @classmethod
    def full(cls) -> StateMask:
        """Every field and every "pos" attachment."""
        everything = frozenset(range(SENSORS))
        flags = {f.name: True for f in fields(cls) if f.name not in ("ir", "sonar")}
        return cls(ir=everything, sonar=everything, **flags)

    def to_bytes(self) -> bytes:
        """The seven CT payload bytes; every byte is filled LSB first."""
        ir = sum(1 << i for i in self.ir)
        sonar = sum(1 << i for i in self.sonar)
        byte4 = sum(1 << bit for bit, name in enumerate(_BYTE4) if getattr(self, name))
        byte6 = sum(1 << bit for bit, name in enumerate(_BYTE6) if getattr(self, name))
        return bytes((ir & 0xFF, ir >> 8, sonar & 0xFF, sonar >> 8, byte4, int(self.laser), byte6))

    @classmethod
    def from_bytes(cls, data: bytes) -> StateMask:
        """Inverse of ``to_bytes``; bits no field uses must be clear, or we would lose them."""
        if len(data) != MASK_SIZE:
            raise PayloadError(f"ct: state mask must be {MASK_SIZE} bytes, got {len(data)}")
        unused = ((5, 0xFE), (6, 0xC0))
        for index, bits in unused:
            if data[index] & bits:
                raise PayloadError(
                    f"ct: mask byte {index} = 0x{data[index]:02X} sets unused bits "
                    f"0x{data[index] & bits:02X}"
                )
        ir = data[0] | data[1] << 8
        sonar = data[2] | data[3] << 8
        flags = {name: bool(data[4] >> bit & 1) for bit, name in enumerate(_BYTE4)}
        flags |= {name: bool(data[6] >> bit & 1) for bit, name in enumerate(_BYTE6)}
        return cls(
            ir=frozenset(i for i in range(SENSORS) if ir >> i & 1),
            sonar=frozenset(i for i in range(SENSORS) if sonar >> i & 1),
            laser=bool(data[5] & 1),
            **flags,
        )


@dataclass(frozen=True)
class PosData:
    """A "pos" attachment: where the robot was and how it moved when a sensor read.

    Units are the protocol's: 1/10 inch, 1/10 degree and per second; times in controller ms.
    """

    x: int = 0
    y: int = 0
    steer: int = 0
    turret: int = 0
    vel_trans: int = 0
    vel_steer: int = 0
    vel_turret: int = 0
    config_time: int = 0
    sense_time: int = 0

    def encode(self, name: str = "pos") -> bytes:
        signed = (
            self.x,
            self.y,
            self.steer,
            self.turret,
            self.vel_trans,
            self.vel_steer,
            self.vel_turret,
        )
        names = ("x", "y", "steer", "turret", "vel_trans", "vel_steer", "vel_turret")
        out = b"".join(encode_s32(v, f"{name}.{n}") for v, n in zip(signed, names, strict=True))
        return (
            out
            + encode_u32(self.config_time, f"{name}.config_time")
            + encode_u32(self.sense_time, f"{name}.sense_time")
        )

    @classmethod
    def read(cls, reader: Reader, name: str = "pos") -> PosData:
        names = ("x", "y", "steer", "turret", "vel_trans", "vel_steer", "vel_turret")
        values = {n: reader.s32(f"{name}.{n}") for n in names}
        return cls(
            **values,
            config_time=reader.u32(f"{name}.config_time"),
            sense_time=reader.u32(f"{name}.sense_time"),
        )


def encode_bumper(value: int, name: str) -> bytes:
    """The 24 bumper bits, most significant byte first: the Nomad 200 sends them reversed."""
    number = check_range(value, 0, U24_MAX, name, "unsigned 24-bit")
    return number.to_bytes(3, "big")


def read_bumper(reader: Reader, name: str) -> int:
    b0, b1, b2 = reader.take(3, name)
    return b2 + 256 * b1 + 65536 * b0


def _tuple16(value: Iterable[Any], name: str) -> tuple[Any, ...]:
    items = tuple(value)
    if len(items) != SENSORS:
        raise ValueError(f"{name} must have {SENSORS} entries (None if absent), got {len(items)}")
    return items


@dataclass(frozen=True)
class State:
    """A decoded state reply. Fields the mask left out are None; units are the protocol's.

    ``ir``, ``ir_pos``, ``sonar`` and ``sonar_pos`` always have 16 entries, indexed by sensor.
    ``motor_status`` bits 0/1/2 are the translation/steering/turret motors; ``clock_ms`` is the
    controller clock; the voltages are raw bytes (see ``units.cpu_voltage``).
    """

    motor_status: int = 0
    clock_ms: int = 0
    cpu_voltage_raw: int = 0
    motor_voltage_raw: int = 0
    ir: tuple[int | None, ...] = NO_READING
    ir_pos: tuple[PosData | None, ...] = NO_READING
    sonar: tuple[int | None, ...] = NO_READING
    sonar_pos: tuple[PosData | None, ...] = NO_READING
    bumper: int | None = None
    bumper_pos: PosData | None = None
    x: int | None = None
    y: int | None = None
    steer: int | None = None
    turret: int | None = None
    vel_trans: int | None = None
    vel_steer: int | None = None
    vel_turret: int | None = None
    compass: int | None = None
    compass_pos: PosData | None = None
    laser: tuple[int, ...] | None = None
    laser_pos: PosData | None = None

    def __post_init__(self) -> None:
        for name in _PER_SENSOR:
            object.__setattr__(self, name, _tuple16(getattr(self, name), f"state.{name}"))
        if self.laser is not None:
            object.__setattr__(self, "laser", tuple(self.laser))

    @property
    def motors_active(self) -> tuple[bool, bool, bool]:
        """Translation, steering and turret motor active, from ``motor_status``."""
        return (
            bool(self.motor_status & 1),
            bool(self.motor_status & 2),
            bool(self.motor_status & 4),
        )


# A segment reads its part of the payload into ``values`` and writes it from a State.
_Read = Callable[[Reader, dict[str, Any]], None]
_Write = Callable[[State], bytes]


@dataclass(frozen=True)
class _Segment:
    name: str
    read: _Read
    write: _Write
    size: int | None  # None when the size depends on the data (the laser)


def _present(value: Any, name: str) -> Any:
    if value is None:
        raise ValueError(f"{name} is None but the state mask includes it")
    return value


def _ir_segment(indices: tuple[int, ...]) -> _Segment:
    def read(reader: Reader, values: dict[str, Any]) -> None:
        packed = reader.take((len(indices) + 1) // 2, "ir readings")
        for k, sensor in enumerate(indices):
            byte = packed[k // 2]
            values["ir"][sensor] = byte & 0x0F if k % 2 == 0 else byte >> 4
        # An odd count leaves a high nibble of padding; it carries nothing, so it is not checked.

    def write(state: State) -> bytes:
        nibbles = [
            check_range(_present(state.ir[s], f"state.ir[{s}]"), 0, IR_MAX, f"state.ir[{s}]", "IR")
            for s in indices
        ]
        nibbles += [0] * (len(nibbles) % 2)
        return bytes(lo | hi << 4 for lo, hi in zip(nibbles[::2], nibbles[1::2], strict=True))

    return _Segment("ir", read, write, (len(indices) + 1) // 2)


def _indexed(attr: str, index: int | None) -> tuple[str, Callable[[State], Any]]:
    if index is None:
        return f"state.{attr}", lambda state: getattr(state, attr)
    return f"state.{attr}[{index}]", lambda state: getattr(state, attr)[index]


def _store(values: dict[str, Any], attr: str, index: int | None, value: Any) -> None:
    if index is None:
        values[attr] = value
    else:
        values[attr][index] = value


def _pos_segment(attr: str, index: int | None = None) -> _Segment:
    name, get = _indexed(attr, index)

    def read(reader: Reader, values: dict[str, Any]) -> None:
        _store(values, attr, index, PosData.read(reader, name))

    def write(state: State) -> bytes:
        pos = _present(get(state), name)
        return pos.encode(name)

    return _Segment(name, read, write, POS_SIZE)


# Fixed-size integer fields: encoder, reader and size, by kind.
_INT_KINDS: dict[str, tuple[Callable[[int, str], bytes], Callable[[Reader, str], int], int]] = {
    "u8": (encode_u8, Reader.u8, 1),
    "u16": (encode_u16, Reader.u16, 2),
    "s16": (encode_s16, Reader.s16, 2),
    "u32": (encode_u32, Reader.u32, 4),
    "bumper": (encode_bumper, read_bumper, 3),
}


def _int_segment(attr: str, kind: str, index: int | None = None) -> _Segment:
    name, get = _indexed(attr, index)
    encode, decode, size = _INT_KINDS[kind]

    def read(reader: Reader, values: dict[str, Any]) -> None:
        _store(values, attr, index, decode(reader, name))

    def write(state: State) -> bytes:
        return encode(_present(get(state), name), name)

    return _Segment(name, read, write, size)


def _laser_segment() -> _Segment:
    def read(reader: Reader, values: dict[str, Any]) -> None:
        count = reader.u16("laser count")
        values["laser"] = tuple(reader.u16(f"state.laser[{k}]") for k in range(count))

    def write(state: State) -> bytes:
        points = _present(state.laser, "state.laser")
        count = encode_u16(len(points), "len(state.laser)")
        return count + b"".join(encode_u16(p, f"state.laser[{k}]") for k, p in enumerate(points))

    return _Segment("laser", read, write, None)


def _segments(mask: StateMask) -> list[_Segment]:
    """The reply's fields in wire order, for this mask."""
    ir, sonar = tuple(sorted(mask.ir)), tuple(sorted(mask.sonar))
    out: list[_Segment] = []
    if ir:
        out.append(_ir_segment(ir))
    if mask.pos_ir:
        out += [_pos_segment("ir_pos", s) for s in ir]
    out += [_int_segment("sonar", "u8", s) for s in sonar]
    if mask.pos_sonar:
        out += [_pos_segment("sonar_pos", s) for s in sonar]
    if mask.bumper:
        out.append(_int_segment("bumper", "bumper"))
        if mask.pos_bumper:
            out.append(_pos_segment("bumper_pos"))
    for attr in ("x", "y", "steer", "turret", "vel_trans", "vel_steer", "vel_turret"):
        if getattr(mask, attr):
            out.append(_int_segment(attr, "s16"))
    if mask.compass:
        out.append(_int_segment("compass", "u16"))
        if mask.pos_compass:
            out.append(_pos_segment("compass_pos"))
    if mask.laser:
        out.append(_laser_segment())
        if mask.pos_laser:
            out.append(_pos_segment("laser_pos"))
    out += [
        _int_segment("motor_status", "u8"),
        _int_segment("clock_ms", "u32"),
        _int_segment("cpu_voltage_raw", "u8"),
        _int_segment("motor_voltage_raw", "u8"),
    ]
    return out


class StateLayout:
    """The byte layout of a state reply under one mask, for decoding and encoding alike."""

    def __init__(self, mask: StateMask) -> None:
        self.mask = mask
        self._segments = tuple(_segments(mask))

    @property
    def field_names(self) -> tuple[str, ...]:
        """The fields in wire order (e.g. ``state.sonar[3]``), for logs and emulator authors."""
        return tuple(s.name for s in self._segments)

    @property
    def size(self) -> int | None:
        """Payload size in bytes, or None if the mask includes the variable-length laser."""
        sizes = [s.size for s in self._segments]
        return None if None in sizes else sum(s for s in sizes if s is not None)

    def decode(self, payload: bytes, what: str = "state reply") -> State:
        reader = Reader(payload, what)
        values: dict[str, Any] = {name: [None] * SENSORS for name in _PER_SENSOR}
        for segment in self._segments:
            segment.read(reader, values)
        reader.finish()
        return State(**values)

    def encode(self, state: State) -> bytes:
        """The payload for ``state``, checked against the mask.

        Raises ValueError naming the field if a value is out of range, is None where the mask
        includes it, or is set where the mask leaves it out (it would be silently lost).
        """
        payload = b"".join(segment.write(state) for segment in self._segments)
        self._check_nothing_lost(state, self.decode(payload))
        return payload

    @staticmethod
    def _check_nothing_lost(state: State, echo: State) -> None:
        # Every field the mask includes survives the round trip exactly, so any difference is a
        # value the mask leaves out.
        for f in fields(State):
            mine, wire = getattr(state, f.name), getattr(echo, f.name)
            if mine == wire:
                continue
            if f.name in _PER_SENSOR:
                k = next(k for k in range(SENSORS) if mine[k] != wire[k])
                raise ValueError(
                    f"state.{f.name}[{k}] = {mine[k]!r} but the state mask leaves it out"
                )
            raise ValueError(f"state.{f.name} = {mine!r} but the state mask leaves it out")

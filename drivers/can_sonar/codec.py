"""Pure codec for the CAN ultrasonic sonar board (modelled on the Neobotix USBoard).

Why a codec over a DBC: the frame layouts live in ``usboard.dbc`` as data that cantools (and any
bus analyser) reads. This module adds only what a DBC cannot say: identifiers relative to a
configurable base, 12-bit readings split over two signals, scaling that depends on a resolution
field, the reserved reading values and the nine-frame parameter set. It holds no bus and no clock
and does no I/O beyond reading the DBC once at import, so the host driver and a board emulator can
share it: every frame encodes and decodes in both directions (host commands and board replies).

Decisions about the protocol (the DBC comments say the same, next to the fields concerned):

* Identifiers. The DBC holds the identifiers for the default base 0x400 (commands at base,
  replies at base + offset), so the file is directly usable on a board left at its default. The
  codec maps ``wire id = DBC id - 0x400 + base`` for the base it is built with, which must leave
  base + 16 a standard 11-bit identifier (base <= 0x7EF).
* Readings. A group data reading is ``low + 256 * high`` (12 bits) counts of the frame's
  resolution, and the resolution is a fraction of a cm (1, 1/2, 1/4, 1/8 cm per count). The
  public driver combines the parts with a shift of 4 and keeps the resolution as an integer; both
  look like defects (a shift of 4 makes the high part overlap the low byte, an integer cannot hold
  0.5 cm), so this codec follows the reference instead.
* Reserved readings. Whole-reading values 0, 1, 2 mean invalid, too close and no echo: they give a
  `Reading` with that `ReadingStatus` and ``range_m = None``, never a distance. Legacy frames (one
  byte per sensor in cm) use the same reserved values: 1 and 2 cm lie below any ultrasonic
  minimum range, so nothing measurable is lost.
* Length. The reference gives no DLC: every frame is 8 bytes, bytes it does not describe are sent
  as 0 and ignored on receipt. A frame of another length is rejected.
* Numbering. Groups 0-3, sensors 0-15, legacy blocks 0-3 and parameter frames 0-8 count from 0
  in this API (bit n of a mask is sensor or group n); signal names in the DBC count from 1 like
  the reference.
* Units. SI throughout: metres, seconds, bit/s. Analog inputs stay raw 12-bit ADC counts because
  the reference gives no reference voltage.
* Quantisation. Encoding a measured range rounds to the nearest count (the sensor quantises
  anyway); configuration values must lie exactly on their grid (0.05 s, 0.01 s, 0.01 m) so a
  parameter set written to the board reads back unchanged.
* Parameter set layout, write acknowledgements (+8 answers writes to RAM, +9 writes to EEPROM,
  byte 1 the frame index), their 16-bit byte sum (sum of the 54 parameter bytes, modulo 65536,
  in the acknowledgement of frame 8 only) and the analog frame's packing are not given by the
  reference: they are this project's choices, written down in the DBC.
* Signal source. 0xF in the group frame means normal mode (``source = None``); otherwise exactly
  one bit k is set and ``source = k``. Any other value is a corrupt frame.
* Heartbeat timing (CONNECT every `CONNECT_INTERVAL_S`, connected while replies come within
  `CONNECT_TIMEOUT_INTERVALS` intervals) is stated here as data for the driver; the codec keeps
  no time.
"""

from __future__ import annotations

import enum
import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from importlib import resources
from typing import Final, TypeAlias

import cantools
from cantools.database import errors as cantools_errors
from cantools.database.can import Database, Message, Signal

DEFAULT_BASE_ID: Final = 0x400
#: The base the identifiers in ``usboard.dbc`` are written for.
DBC_BASE_ID: Final = 0x400
#: The largest base whose highest reply (base + 16) is still a standard identifier.
MAX_BASE_ID: Final = 0x7FF - 16
FRAME_LENGTH: Final = 8
SENSOR_COUNT: Final = 16
GROUP_COUNT: Final = 4
SENSORS_PER_GROUP: Final = 4
PARASET_FRAME_COUNT: Final = 9
PARASET_PAYLOAD_LENGTH: Final = 6
CONNECT_INTERVAL_S: Final = 1.0
CONNECT_TIMEOUT_INTERVALS: Final = 3
#: Bitrate in bit/s -> the board's bitrate code.
BITRATE_CODES: Final[dict[int, int]] = {
    1_000_000: 0,
    500_000: 1,
    250_000: 2,
    125_000: 3,
    100_000: 4,
    50_000: 5,
}
DEFAULT_FIRE_INTERVAL_S: Final = 0.02
_MAX_READING_COUNTS: Final = 0xFFF
_NORMAL_SOURCE: Final = 0xF


class CanSonarError(Exception):
    """Base of every error this codec raises, so callers can catch the protocol as a whole."""


class FrameError(CanSonarError):
    """A received frame (or set of frames) does not fit the protocol: it must not be trusted."""


class UnknownIdentifierError(FrameError):
    """The identifier is not one of this board's: on a shared bus such frames are simply skipped."""


class EncodeError(CanSonarError, ValueError):
    """A value cannot be put on the wire (out of range, off the grid, wrong type)."""


# --- the DBC ------------------------------------------------------------------------------------


def _load_database() -> Database:
    package = __package__ or "drivers.can_sonar"
    text = resources.files(package).joinpath("usboard.dbc").read_text(encoding="ascii")
    db = cantools.database.load_string(text, database_format="dbc")
    if not isinstance(db, Database):  # pragma: no cover - load_string's union return type
        raise TypeError("usboard.dbc did not load as a CAN database")
    return db


_DB: Final = _load_database()
_MSG: Final[dict[str, Message]] = {m.name: m for m in _DB.messages}
_BY_OFFSET: Final[dict[int, Message]] = {m.frame_id - DBC_BASE_ID: m for m in _DB.messages}
_COMMAND_MSG: Final = _MSG["HostCommand"]
_PARASET_MSG: Final = _MSG["ParameterSet"]
_ANALOG_MSG: Final = _MSG["AnalogInputs"]
_LEGACY_MSGS: Final = tuple(_MSG[f"LegacyData{b + 1}"] for b in range(4))
_GROUP_MSGS: Final = tuple(_MSG[f"GroupData{g + 1}"] for g in range(GROUP_COUNT))
_ACK_MSGS: Final = {False: _MSG["WriteAckRam"], True: _MSG["WriteAckEeprom"]}


def database() -> Database:
    """The loaded ``usboard.dbc`` (shared, do not modify): for tools and cross-checks."""
    return _DB


def _signal(message: Message, name: str) -> Signal:
    return message.get_signal_by_name(name)


def _inverse_scale(signal: Signal) -> int:
    """Counts per unit: every scale in the DBC is 1/n, so dividing by n keeps values exact."""
    return round(1 / signal.scale)


def _raw_bounds(signal: Signal) -> tuple[int, int]:
    inv = _inverse_scale(signal)
    offset = round(signal.offset * inv)
    lo = 0 if signal.minimum is None else round(signal.minimum * inv) - offset
    hi = (
        (1 << signal.length) - 1 if signal.maximum is None else round(signal.maximum * inv) - offset
    )
    return lo, hi


def _to_si(signal: Signal, raw: int) -> float:
    inv = _inverse_scale(signal)
    return (raw + round(signal.offset * inv)) / inv


def _from_si(signal: Signal, value: float, what: str) -> int:
    """Raw value of a configuration field: it must lie on the field's grid and in its range."""
    unit = f" {signal.unit}" if signal.unit else ""
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise EncodeError(f"{what} must be a finite number, got {value!r}")
    inv = _inverse_scale(signal)
    counts = value * inv
    nearest = round(counts)
    if abs(counts - nearest) > 1e-6:
        raise EncodeError(f"{what} = {value}{unit} is not a multiple of {signal.scale}{unit}")
    raw = nearest - round(signal.offset * inv)
    lo, hi = _raw_bounds(signal)
    if not lo <= raw <= hi:
        raise EncodeError(
            f"{what} = {value}{unit} is outside {_to_si(signal, lo)}..{_to_si(signal, hi)}{unit}"
        )
    return raw


def _check_int(value: object, lo: int, hi: int, what: str) -> int:
    if isinstance(value, bool) or not isinstance(value, int):
        raise EncodeError(f"{what} must be an int, got {value!r}")
    if not lo <= value <= hi:
        raise EncodeError(f"{what} = {value} is outside {lo}..{hi}")
    return value


def _encode(message: Message, values: dict[str, int]) -> bytes:
    try:
        return message.encode(values, scaling=False, padding=False, strict=True)
    except (cantools_errors.EncodeError, KeyError, ValueError) as exc:
        raise EncodeError(f"cannot encode {message.name}: {exc}") from exc


def _decode(message: Message, data: bytes) -> dict[str, int]:
    """Raw signal values, each checked against the DBC range so bad fields name themselves."""
    try:
        decoded = message.decode(data, decode_choices=False, scaling=False)
    except (cantools_errors.DecodeError, KeyError, ValueError) as exc:
        raise FrameError(f"cannot decode {message.name}: {exc}") from exc
    values: dict[str, int] = {}
    for name, value in decoded.items():
        raw = int(value)  # type: ignore[arg-type]  # unscaled integer signals only
        signal = _signal(message, name)
        lo, hi = _raw_bounds(signal)
        if not lo <= raw <= hi:
            raise FrameError(
                f"{message.name} frame: {name} = {raw} is outside its range {lo}..{hi}"
            )
        values[name] = raw
    return values


# --- values -------------------------------------------------------------------------------------


@dataclass(frozen=True, slots=True)
class Frame:
    """One standard-identifier CAN frame, free of any CAN library so the codec stays pure."""

    arbitration_id: int
    data: bytes

    def __post_init__(self) -> None:
        object.__setattr__(self, "data", bytes(self.data))


class CommandCode(enum.IntEnum):
    """Byte 0 of every host-to-board frame."""

    CONNECT = 0
    SET_CHANNEL_ACTIVE = 1
    GET_DATA_1_TO_8 = 2
    GET_DATA_9_TO_16 = 3
    WRITE_PARASET_RAM = 4
    WRITE_PARASET_EEPROM = 5
    READ_PARASET = 6
    GET_ANALOG_IN = 7
    GET_DATA = 13


class Resolution(enum.IntEnum):
    """Resolution code of a group data frame: the distance of one count is a fraction of a cm."""

    CM_1 = 0
    CM_0_5 = 1
    CM_0_25 = 2
    CM_0_125 = 3

    @property
    def counts_per_metre(self) -> int:
        """100, 200, 400, 800: an integer, so ``counts / counts_per_metre`` is exact to 1 ulp."""
        return 100 << self.value

    @property
    def metres_per_count(self) -> float:
        """0.01, 0.005, 0.0025, 0.00125 m."""
        return 1 / self.counts_per_metre


class ReadingStatus(enum.Enum):
    """Whether a reading holds a distance, and if not, which reserved value the board sent."""

    OK = "ok"
    INVALID = "invalid"
    TOO_CLOSE = "too close"
    NO_ECHO = "no echo"


_RESERVED: Final = {0: ReadingStatus.INVALID, 1: ReadingStatus.TOO_CLOSE, 2: ReadingStatus.NO_ECHO}
_RESERVED_RAW: Final = {status: raw for raw, status in _RESERVED.items()}
_FIRST_DISTANCE_COUNT: Final = max(_RESERVED) + 1


@dataclass(frozen=True, slots=True)
class Reading:
    """One sensor's reading: a range in metres, or a reason there is none (never a fake 0 m)."""

    status: ReadingStatus
    range_m: float | None = None

    def __post_init__(self) -> None:
        if self.status is ReadingStatus.OK:
            if self.range_m is None or not math.isfinite(self.range_m) or self.range_m < 0:
                raise EncodeError(f"an OK reading needs a finite range >= 0, got {self.range_m!r}")
        elif self.range_m is not None:
            raise EncodeError(f"a {self.status.value!r} reading has no range, got {self.range_m}")

    @classmethod
    def ok(cls, range_m: float) -> Reading:
        """A reading that holds a distance."""
        return cls(ReadingStatus.OK, range_m)


def _reading_from_counts(counts: int, counts_per_metre: int) -> Reading:
    status = _RESERVED.get(counts)
    if status is not None:
        return Reading(status)
    return Reading.ok(counts / counts_per_metre)


def _counts_from_reading(
    reading: Reading, counts_per_metre: int, max_counts: int, what: str
) -> int:
    if not isinstance(reading, Reading):
        raise EncodeError(f"{what} must be a Reading, got {reading!r}")
    if reading.status is not ReadingStatus.OK:
        return _RESERVED_RAW[reading.status]
    assert reading.range_m is not None  # guaranteed by Reading.__post_init__
    counts = round(reading.range_m * counts_per_metre)
    if counts < _FIRST_DISTANCE_COUNT:
        raise EncodeError(
            f"{what}: {reading.range_m} m is {counts} counts at {1 / counts_per_metre} m per count,"
            f" which would be sent as a reserved value; send ReadingStatus.TOO_CLOSE instead"
        )
    if counts > max_counts:
        raise EncodeError(
            f"{what}: {reading.range_m} m is beyond {max_counts / counts_per_metre} m, the largest"
            f" range at {1 / counts_per_metre} m per count"
        )
    return counts


def _four_readings(readings: Sequence[Reading], owner: str) -> tuple[Reading, ...]:
    readings = tuple(readings)
    if len(readings) != SENSORS_PER_GROUP or not all(isinstance(r, Reading) for r in readings):
        raise EncodeError(f"{owner} needs exactly 4 Reading values, got {readings!r}")
    return readings


@dataclass(frozen=True, slots=True)
class ParasetChunk:
    """One of the nine frames of a parameter set: its index and six parameter bytes.

    Kept as bytes so the byte sum of the write acknowledgement is computed over exactly what
    travelled, and so an emulator can store a write before interpreting it.
    """

    index: int
    payload: bytes

    def __post_init__(self) -> None:
        _check_int(self.index, 0, PARASET_FRAME_COUNT - 1, "parameter set frame index")
        object.__setattr__(self, "payload", bytes(self.payload))
        if len(self.payload) != PARASET_PAYLOAD_LENGTH:
            raise EncodeError(
                f"parameter set frame {self.index} needs 6 payload bytes, got {len(self.payload)}"
            )


@dataclass(frozen=True, slots=True)
class ParameterSet:
    """The configuration the board holds, in SI units (seconds, metres, bit/s).

    Values are checked when encoded (`paraset_to_chunks`), against the field ranges in the DBC.
    """

    update_interval_s: float
    warning_distances_m: tuple[float, ...]
    alarm_distances_m: tuple[float, ...]
    cross_echo: bool = False
    fire_intervals_s: tuple[float, ...] = (DEFAULT_FIRE_INTERVAL_S,) * GROUP_COUNT
    bitrate: int = 1_000_000
    base_id: int = DEFAULT_BASE_ID

    def __post_init__(self) -> None:
        for name, count in (
            ("warning_distances_m", SENSOR_COUNT),
            ("alarm_distances_m", SENSOR_COUNT),
            ("fire_intervals_s", GROUP_COUNT),
        ):
            values = tuple(getattr(self, name))
            if len(values) != count:
                raise EncodeError(f"{name} needs {count} values, got {len(values)}")
            object.__setattr__(self, name, values)


# --- host -> board ------------------------------------------------------------------------------


@dataclass(frozen=True, slots=True)
class Connect:
    """CONNECT: the host's heartbeat, sent every second."""


@dataclass(frozen=True, slots=True)
class SetChannelActive:
    """SET_CHANNEL_ACTIVE: bit n of ``mask`` set = sensor n (0-15) fires."""

    mask: int

    def __post_init__(self) -> None:
        _check_int(self.mask, 0, (1 << SENSOR_COUNT) - 1, "active sensor mask")


@dataclass(frozen=True, slots=True)
class GetLegacyData:
    """GET_DATA 1-8 (bank 0) or 9-16 (bank 1): the board answers with two legacy data frames."""

    bank: int

    def __post_init__(self) -> None:
        _check_int(self.bank, 0, 1, "legacy data bank")


@dataclass(frozen=True, slots=True)
class WriteParaset:
    """WRITE_PARASET: one of nine frames, to RAM or (``eeprom=True``) to EEPROM."""

    chunk: ParasetChunk
    eeprom: bool = False


@dataclass(frozen=True, slots=True)
class ReadParaset:
    """READ_PARASET: the board answers with the nine parameter set frames."""


@dataclass(frozen=True, slots=True)
class GetAnalogIn:
    """GET_ANALOG_IN: the board answers with one analog inputs frame."""


@dataclass(frozen=True, slots=True)
class GetData:
    """GET_DATA: one group data frame per requested group (0-3); sorted, unique, at least one."""

    groups: tuple[int, ...]

    def __post_init__(self) -> None:
        groups = tuple(sorted({_check_int(g, 0, GROUP_COUNT - 1, "group") for g in self.groups}))
        if not groups:
            raise EncodeError("GET_DATA needs at least one group")
        object.__setattr__(self, "groups", groups)


Command: TypeAlias = (
    Connect | SetChannelActive | GetLegacyData | WriteParaset | ReadParaset | GetAnalogIn | GetData
)


# --- board -> host ------------------------------------------------------------------------------


@dataclass(frozen=True, slots=True)
class ConnectReply:
    """Reply to CONNECT: its arrival is the heartbeat; it carries nothing."""


@dataclass(frozen=True, slots=True)
class LegacyData:
    """Legacy data frame: sensors 4*block .. 4*block+3, 1 cm per count, at most 2.55 m."""

    block: int
    readings: tuple[Reading, ...]

    def __post_init__(self) -> None:
        _check_int(self.block, 0, SENSOR_COUNT // SENSORS_PER_GROUP - 1, "legacy data block")
        object.__setattr__(self, "readings", _four_readings(self.readings, "legacy data"))


@dataclass(frozen=True, slots=True)
class ParasetData:
    """One frame of the parameter set the board reports after READ_PARASET."""

    chunk: ParasetChunk


@dataclass(frozen=True, slots=True)
class AnalogIn:
    """The four analog inputs, raw 12-bit ADC counts."""

    counts: tuple[int, ...]

    def __post_init__(self) -> None:
        counts = tuple(self.counts)
        if len(counts) != 4:
            raise EncodeError(f"analog inputs need 4 values, got {len(counts)}")
        for k, c in enumerate(counts):
            _check_int(c, 0, _MAX_READING_COUNTS, f"analog input {k}")
        object.__setattr__(self, "counts", counts)


@dataclass(frozen=True, slots=True)
class WriteAck:
    """Acknowledgement of one WRITE_PARASET frame; the one for frame 8 carries the byte sum."""

    index: int
    eeprom: bool = False
    byte_sum: int | None = None

    def __post_init__(self) -> None:
        _check_int(self.index, 0, PARASET_FRAME_COUNT - 1, "acknowledged frame index")
        final = self.index == PARASET_FRAME_COUNT - 1
        if final and self.byte_sum is None:
            raise EncodeError("the acknowledgement of frame 8 must carry the byte sum")
        if not final and self.byte_sum is not None:
            raise EncodeError(
                f"only the acknowledgement of frame 8 carries a byte sum, not {self.index}"
            )
        if self.byte_sum is not None:
            _check_int(self.byte_sum, 0, 0xFFFF, "byte sum")


@dataclass(frozen=True, slots=True)
class GroupData:
    """One group's data frame: four readings of sensors 4*group .. 4*group+3.

    ``source`` is None in normal mode, else the index (0-3) of the signal source the board names.
    """

    group: int
    resolution: Resolution
    readings: tuple[Reading, ...]
    source: int | None = None

    def __post_init__(self) -> None:
        _check_int(self.group, 0, GROUP_COUNT - 1, "group")
        try:
            object.__setattr__(self, "resolution", Resolution(self.resolution))
        except ValueError as exc:
            raise EncodeError(f"unknown resolution code {self.resolution!r}") from exc
        object.__setattr__(self, "readings", _four_readings(self.readings, "group data"))
        if self.source is not None:
            _check_int(self.source, 0, 3, "signal source")


Reply: TypeAlias = ConnectReply | LegacyData | ParasetData | AnalogIn | WriteAck | GroupData


# --- parameter sets -----------------------------------------------------------------------------


def _paraset_signals(index: int) -> list[str]:
    return [
        s.name
        for s in _PARASET_MSG.signals
        if s.multiplexer_ids is not None and index in s.multiplexer_ids
    ]


_PARASET_BRANCHES: Final = {i: _paraset_signals(i) for i in range(PARASET_FRAME_COUNT)}


def _paraset_raw(params: ParameterSet) -> dict[str, int]:
    if not isinstance(params, ParameterSet):
        raise EncodeError(f"expected a ParameterSet, got {params!r}")
    sig = _PARASET_MSG.get_signal_by_name
    if params.bitrate not in BITRATE_CODES:
        raise EncodeError(
            f"bitrate {params.bitrate!r} bit/s is not one the board knows: {sorted(BITRATE_CODES)}"
        )
    if not isinstance(params.cross_echo, bool):
        raise EncodeError(f"cross_echo must be a bool, got {params.cross_echo!r}")
    raw = {
        "BitrateCode": BITRATE_CODES[params.bitrate],
        "BaseIdentifier": _check_int(params.base_id, 0, MAX_BASE_ID, "base identifier"),
        "UpdateInterval": _from_si(
            sig("UpdateInterval"), params.update_interval_s, "update interval"
        ),
        "CrossEchoMode": int(params.cross_echo),
    }
    for g, interval in enumerate(params.fire_intervals_s):
        name = f"FireIntervalGroup{g + 1}"
        raw[name] = _from_si(sig(name), interval, f"fire interval of group {g}")
    for n in range(SENSOR_COUNT):
        for kind, values in (
            ("Warning", params.warning_distances_m),
            ("Alarm", params.alarm_distances_m),
        ):
            name = f"{kind}DistanceSensor{n + 1}"
            raw[name] = _from_si(sig(name), values[n], f"{kind.lower()} distance of sensor {n}")
    return raw


def paraset_to_chunks(params: ParameterSet) -> tuple[ParasetChunk, ...]:
    """The nine frames' payloads of a parameter set, laid out by the DBC's ParameterSet message."""
    raw = _paraset_raw(params)
    chunks = []
    for index, names in _PARASET_BRANCHES.items():
        data = _encode(_PARASET_MSG, {"ParasetFrameIndex": index, **{n: raw[n] for n in names}})
        chunks.append(ParasetChunk(index, data[2:]))
    return tuple(chunks)


def _chunk_values(chunk: ParasetChunk) -> dict[str, int]:
    return _decode(_PARASET_MSG, bytes([0, chunk.index]) + chunk.payload)


def _check_chunk_for_encoding(chunk: ParasetChunk) -> None:
    if not isinstance(chunk, ParasetChunk):
        raise EncodeError(f"expected a ParasetChunk, got {chunk!r}")
    try:
        _chunk_values(chunk)
    except FrameError as exc:
        raise EncodeError(str(exc)) from exc


def paraset_from_chunks(chunks: Iterable[ParasetChunk]) -> ParameterSet:
    """Assemble nine frames (any order, each index once) into a parameter set; FrameError if not."""
    by_index: dict[int, ParasetChunk] = {}
    for chunk in chunks:
        if chunk.index in by_index:
            raise FrameError(f"parameter set frame {chunk.index} appears twice")
        by_index[chunk.index] = chunk
    missing = sorted(set(range(PARASET_FRAME_COUNT)) - by_index.keys())
    if missing:
        raise FrameError(f"parameter set incomplete: frame(s) {missing} missing")
    raw: dict[str, int] = {}
    for chunk in by_index.values():
        raw.update(_chunk_values(chunk))
    sig = _PARASET_MSG.get_signal_by_name
    bitrates = {code: bitrate for bitrate, code in BITRATE_CODES.items()}
    return ParameterSet(
        update_interval_s=_to_si(sig("UpdateInterval"), raw["UpdateInterval"]),
        warning_distances_m=tuple(
            _to_si(sig(f"WarningDistanceSensor{n + 1}"), raw[f"WarningDistanceSensor{n + 1}"])
            for n in range(SENSOR_COUNT)
        ),
        alarm_distances_m=tuple(
            _to_si(sig(f"AlarmDistanceSensor{n + 1}"), raw[f"AlarmDistanceSensor{n + 1}"])
            for n in range(SENSOR_COUNT)
        ),
        cross_echo=bool(raw["CrossEchoMode"]),
        fire_intervals_s=tuple(
            _to_si(sig(f"FireIntervalGroup{g + 1}"), raw[f"FireIntervalGroup{g + 1}"])
            for g in range(GROUP_COUNT)
        ),
        bitrate=bitrates[raw["BitrateCode"]],
        base_id=raw["BaseIdentifier"],
    )


def paraset_byte_sum(chunks: Iterable[ParasetChunk]) -> int:
    """The 16-bit sum of the parameter bytes, as the final write acknowledgement carries it."""
    return sum(b for chunk in chunks for b in chunk.payload) & 0xFFFF


# --- the codec ----------------------------------------------------------------------------------


class UsBoardCodec:
    """Frames of one board at a configurable base identifier, in both directions.

    Stateless apart from the base: a host driver and a board emulator each hold one.
    """

    def __init__(self, base_id: int = DEFAULT_BASE_ID) -> None:
        self._base = _check_int(base_id, 0, MAX_BASE_ID, "base identifier")

    @property
    def base_id(self) -> int:
        """The identifier of host commands; replies sit at fixed offsets above it."""
        return self._base

    def __repr__(self) -> str:
        return f"UsBoardCodec(base_id=0x{self._base:03X})"

    # identifiers

    def _wire_id(self, message: Message) -> int:
        return message.frame_id - DBC_BASE_ID + self._base

    def owns(self, arbitration_id: int) -> bool:
        """Whether a frame with this identifier belongs to this board (command or reply)."""
        return (arbitration_id - self._base) in _BY_OFFSET

    def _frame(self, message: Message, data: bytes) -> Frame:
        return Frame(self._wire_id(message), data)

    def _message_of(self, frame: Frame) -> Message:
        """The DBC message of a frame, after checking identifier and length."""
        if not isinstance(frame, Frame):
            raise FrameError(f"expected a Frame, got {frame!r}")
        ident = frame.arbitration_id
        if not isinstance(ident, int) or not 0 <= ident <= 0x7FF:
            raise FrameError(f"identifier {ident!r} is not a standard 11-bit identifier")
        message = _BY_OFFSET.get(ident - self._base)
        if message is None:
            offsets = ", ".join(f"+{o}" for o in sorted(_BY_OFFSET))
            raise UnknownIdentifierError(
                f"identifier 0x{ident:03X} is not a frame of a board at base 0x{self._base:03X}"
                f" (known offsets: {offsets})"
            )
        if len(frame.data) != FRAME_LENGTH:
            raise FrameError(
                f"{message.name} frame 0x{ident:03X} has DLC {len(frame.data)}; every frame of"
                f" this board is {FRAME_LENGTH} bytes"
            )
        return message

    # host -> board: building

    def connect(self) -> Frame:
        """CONNECT, the heartbeat request."""
        return self.encode_command(Connect())

    def set_channels_active(self, mask: int) -> Frame:
        """SET_CHANNEL_ACTIVE with bit n of ``mask`` = sensor n (0-15) active."""
        return self.encode_command(SetChannelActive(mask))

    def get_data(self, groups: Iterable[int]) -> Frame:
        """GET_DATA for the given groups (0-3)."""
        return self.encode_command(GetData(tuple(groups)))

    def get_legacy_data(self, bank: int) -> Frame:
        """Legacy GET_DATA for sensors 0-7 (bank 0) or 8-15 (bank 1)."""
        return self.encode_command(GetLegacyData(bank))

    def write_paraset(self, params: ParameterSet, *, eeprom: bool = False) -> list[Frame]:
        """The nine WRITE_PARASET frames, to RAM or to EEPROM, in index order."""
        return [self.encode_command(WriteParaset(c, eeprom)) for c in paraset_to_chunks(params)]

    def read_paraset(self) -> Frame:
        """READ_PARASET."""
        return self.encode_command(ReadParaset())

    def get_analog_in(self) -> Frame:
        """GET_ANALOG_IN."""
        return self.encode_command(GetAnalogIn())

    def encode_command(self, command: Command) -> Frame:
        """Any host command as a frame at the base identifier."""
        values: dict[str, int]
        match command:
            case Connect():
                values = {"Command": CommandCode.CONNECT, "Unused": 0}
            case SetChannelActive(mask=mask):
                values = {"Command": CommandCode.SET_CHANNEL_ACTIVE, "ActiveSensors": mask}
            case GetLegacyData(bank=bank):
                code = CommandCode.GET_DATA_9_TO_16 if bank else CommandCode.GET_DATA_1_TO_8
                values = {"Command": code, "Unused": 0}
            case WriteParaset(chunk=chunk, eeprom=eeprom):
                _check_chunk_for_encoding(chunk)
                values = {
                    "Command": (
                        CommandCode.WRITE_PARASET_EEPROM
                        if eeprom
                        else CommandCode.WRITE_PARASET_RAM
                    ),
                    "ParasetFrameIndex": chunk.index,
                    "ParasetData": int.from_bytes(chunk.payload, "little"),
                }
            case ReadParaset():
                values = {"Command": CommandCode.READ_PARASET, "Unused": 0}
            case GetAnalogIn():
                values = {"Command": CommandCode.GET_ANALOG_IN, "Unused": 0}
            case GetData(groups=groups):
                values = {"Command": CommandCode.GET_DATA, "RequestedGroups": _mask(groups)}
            case _:
                raise EncodeError(f"not a host command: {command!r}")
        return self._frame(
            _COMMAND_MSG, _encode(_COMMAND_MSG, {k: int(v) for k, v in values.items()})
        )

    # host -> board: reading (the emulator's side)

    def decode_command(self, frame: Frame) -> Command:
        """A host command from its frame; FrameError if the frame is not a valid command."""
        message = self._message_of(frame)
        if message is not _COMMAND_MSG:
            raise FrameError(
                f"identifier 0x{frame.arbitration_id:03X} is the board's {message.name},"
                f" not a host command"
            )
        try:
            code = CommandCode(frame.data[0])
        except ValueError:
            known = ", ".join(f"{c.value} ({c.name})" for c in CommandCode)
            raise FrameError(
                f"unknown command code {frame.data[0]} in frame 0x{frame.arbitration_id:03X};"
                f" known codes: {known}"
            ) from None
        values = _decode(message, frame.data)
        match code:
            case CommandCode.CONNECT:
                return Connect()
            case CommandCode.SET_CHANNEL_ACTIVE:
                return SetChannelActive(values["ActiveSensors"])
            case CommandCode.GET_DATA_1_TO_8 | CommandCode.GET_DATA_9_TO_16:
                return GetLegacyData(int(code == CommandCode.GET_DATA_9_TO_16))
            case CommandCode.WRITE_PARASET_RAM | CommandCode.WRITE_PARASET_EEPROM:
                chunk = ParasetChunk(
                    values["ParasetFrameIndex"],
                    values["ParasetData"].to_bytes(PARASET_PAYLOAD_LENGTH, "little"),
                )
                _chunk_values(chunk)  # reject a bad field now, naming it, not at assembly
                return WriteParaset(chunk, eeprom=code == CommandCode.WRITE_PARASET_EEPROM)
            case CommandCode.READ_PARASET:
                return ReadParaset()
            case CommandCode.GET_ANALOG_IN:
                return GetAnalogIn()
            case CommandCode.GET_DATA:
                mask = values["RequestedGroups"]
                return GetData(tuple(g for g in range(GROUP_COUNT) if mask >> g & 1))
        raise AssertionError(f"unhandled command code {code!r}")  # pragma: no cover

    # board -> host: building (the emulator's side)

    def encode_reply(self, reply: Reply) -> Frame:
        """Any board reply as a frame at its offset from the base."""
        match reply:
            case ConnectReply():
                return self._frame(_MSG["ConnectReply"], bytes(FRAME_LENGTH))
            case LegacyData(block=block, readings=readings):
                message = _LEGACY_MSGS[block]
                values = {}
                for k, reading in enumerate(readings):
                    name = f"Sensor{SENSORS_PER_GROUP * block + k + 1}"
                    signal = _signal(message, name)
                    _, hi = _raw_bounds(signal)
                    what = f"legacy reading of sensor {SENSORS_PER_GROUP * block + k}"
                    values[name] = _counts_from_reading(reading, _inverse_scale(signal), hi, what)
                return self._frame(message, _encode(message, values))
            case ParasetData(chunk=chunk):
                _check_chunk_for_encoding(chunk)
                return self._frame(_PARASET_MSG, bytes([0, chunk.index]) + chunk.payload)
            case AnalogIn(counts=counts):
                values = {}
                for k, c in enumerate(counts):
                    values[f"Input{k + 1}Low"] = c & 0xFF
                    values[f"Input{k + 1}High"] = c >> 8
                return self._frame(_ANALOG_MSG, _encode(_ANALOG_MSG, values))
            case WriteAck(index=index, eeprom=eeprom, byte_sum=byte_sum):
                message = _ACK_MSGS[bool(eeprom)]
                values = {"AckFrameIndex": index, "ByteSum": byte_sum or 0}
                return self._frame(message, _encode(message, values))
            case GroupData():
                return self._encode_group(reply)
            case _:
                raise EncodeError(f"not a board reply: {reply!r}")

    def _encode_group(self, reply: GroupData) -> Frame:
        message = _GROUP_MSGS[reply.group]
        source = _NORMAL_SOURCE if reply.source is None else 1 << reply.source
        values = {"Group": reply.group, "Resolution": int(reply.resolution), "SignalSource": source}
        for k, reading in enumerate(reply.readings):
            sensor = SENSORS_PER_GROUP * reply.group + k
            counts = _counts_from_reading(
                reading,
                reply.resolution.counts_per_metre,
                _MAX_READING_COUNTS,
                f"reading of sensor {sensor}",
            )
            values[f"Sensor{sensor + 1}Low"] = counts & 0xFF
            values[f"Sensor{sensor + 1}High"] = counts >> 8
        return self._frame(message, _encode(message, values))

    def paraset_reply(self, params: ParameterSet) -> list[Frame]:
        """The nine parameter set frames a board sends after READ_PARASET, in index order."""
        return [self.encode_reply(ParasetData(c)) for c in paraset_to_chunks(params)]

    # board -> host: reading

    def decode_reply(self, frame: Frame) -> Reply:
        """A board reply from its frame; FrameError if the frame is not a valid reply."""
        message = self._message_of(frame)
        if message is _COMMAND_MSG:
            raise FrameError(
                f"identifier 0x{frame.arbitration_id:03X} is the host command identifier,"
                f" not a board reply"
            )
        values = _decode(message, frame.data)
        if message.name == "ConnectReply":
            return ConnectReply()
        if message in _LEGACY_MSGS:
            block = _LEGACY_MSGS.index(message)
            readings = []
            for k in range(SENSORS_PER_GROUP):
                name = f"Sensor{SENSORS_PER_GROUP * block + k + 1}"
                per_metre = _inverse_scale(_signal(message, name))
                readings.append(_reading_from_counts(values[name], per_metre))
            return LegacyData(block, tuple(readings))
        if message is _PARASET_MSG:
            chunk = ParasetChunk(values["ParasetFrameIndex"], frame.data[2:])
            _chunk_values(chunk)
            return ParasetData(chunk)
        if message is _ANALOG_MSG:
            return AnalogIn(
                tuple(
                    _combine(values[f"Input{k + 1}Low"], values[f"Input{k + 1}High"])
                    for k in range(4)
                )
            )
        if message in _ACK_MSGS.values():
            index = values["AckFrameIndex"]
            final = index == PARASET_FRAME_COUNT - 1
            return WriteAck(
                index,
                eeprom=message is _ACK_MSGS[True],
                byte_sum=values["ByteSum"] if final else None,
            )
        return self._decode_group(frame, message, values)

    def _decode_group(self, frame: Frame, message: Message, values: dict[str, int]) -> GroupData:
        group = _GROUP_MSGS.index(message)
        if values["Group"] != group:
            raise FrameError(
                f"group data frame 0x{frame.arbitration_id:03X} is group {group}'s identifier"
                f" but byte 1 names group {values['Group']}: corrupt frame"
            )
        source_bits = values["SignalSource"]
        if source_bits == _NORMAL_SOURCE:
            source = None
        elif source_bits in (1, 2, 4, 8):
            source = source_bits.bit_length() - 1
        else:
            raise FrameError(
                f"group data frame 0x{frame.arbitration_id:03X}: signal source bits"
                f" 0b{source_bits:04b} are neither 0xF (normal mode) nor a single source bit"
            )
        resolution = Resolution(values["Resolution"])
        readings = []
        for k in range(SENSORS_PER_GROUP):
            sensor = SENSORS_PER_GROUP * group + k + 1
            counts = _combine(values[f"Sensor{sensor}Low"], values[f"Sensor{sensor}High"])
            readings.append(_reading_from_counts(counts, resolution.counts_per_metre))
        return GroupData(group, resolution, tuple(readings), source)

    # either direction

    def decode(self, frame: Frame) -> Command | Reply:
        """Any frame of this board: a command at the base identifier, a reply above it."""
        if isinstance(frame, Frame) and frame.arbitration_id == self._base:
            return self.decode_command(frame)
        return self.decode_reply(frame)


def _combine(low: int, high: int) -> int:
    """A 12-bit value from its low byte and 4-bit high part: low + 256 * high (see module doc)."""
    return low | high << 8


def _mask(indices: Iterable[int]) -> int:
    mask = 0
    for i in indices:
        mask |= 1 << i
    return mask

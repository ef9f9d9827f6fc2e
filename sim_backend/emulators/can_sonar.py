"""The CAN ultrasonic sonar board, emulated on the simulated robot's ring.

``UsBoardEmulator`` is the board's behaviour, frames in and frames out through the drivers'
codec: it answers CONNECT (the heartbeat), SET_CHANNEL_ACTIVE, GET_DATA (group frames) and the
legacy GET_DATA, WRITE_PARASET (one acknowledgement per frame, the byte sum in the last),
READ_PARASET and GET_ANALOG_IN. Its readings are the latest of each simulated transducer:
board channel ``k`` carries transducer ``transducers[k]`` (by default channel k = transducer k,
the ring's own order), NaN (no echo) becomes the reserved *no echo*, a range below three counts
*too close*, an inactive or unconnected channel *invalid*.

``CanSonarDevice`` puts a board on a link (an SLCAN pseudo-terminal or a python-can virtual
channel) with fault injection, as an ``EmulatedDevice`` for ``EmulatorHost``, so it can share
one ``SimRobot`` with a Nomad 200 serial emulator.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any, Protocol

import numpy as np

from drivers.can_sonar.codec import (
    DEFAULT_BASE_ID,
    PARASET_FRAME_COUNT,
    SENSOR_COUNT,
    SENSORS_PER_GROUP,
    AnalogIn,
    CanSonarError,
    Connect,
    ConnectReply,
    Frame,
    GetAnalogIn,
    GetData,
    GetLegacyData,
    GroupData,
    LegacyData,
    ParameterSet,
    ParasetChunk,
    Reading,
    ReadingStatus,
    ReadParaset,
    Resolution,
    SetChannelActive,
    UsBoardCodec,
    WriteAck,
    WriteParaset,
    paraset_byte_sum,
    paraset_from_chunks,
)
from sim_backend.emulators.can_sonar_faults import BoardFaults, BusError, FaultInjector
from sim_backend.emulators.can_sonar_slcan import SlcanPty
from sim_backend.emulators.can_sonar_virtual import VirtualCanChannel
from sim_backend.simulator import SimRobot

_FIRST_DISTANCE_COUNT = 3  # counts 0, 1, 2 are the reserved values
_MAX_COUNTS = 0xFFF
_LEGACY_COUNTS_PER_METRE = 100
_LEGACY_MAX_COUNTS = 0xFF


def default_parameters(base_id: int = DEFAULT_BASE_ID, bitrate: int = 1_000_000) -> ParameterSet:
    """What a board holds out of the box: data every 100 ms, groups fired 20 ms apart."""
    return ParameterSet(
        update_interval_s=0.1,
        warning_distances_m=(0.5,) * SENSOR_COUNT,
        alarm_distances_m=(0.3,) * SENSOR_COUNT,
        bitrate=bitrate,
        base_id=base_id,
    )


@dataclass
class BoardCounts:
    commands: int = 0
    bad_commands: int = 0
    foreign_frames: int = 0
    replies: int = 0
    connects_ignored: int = 0
    parameter_sets_written: int = 0


class UsBoardEmulator:
    """The board: host commands in, board replies out. ``ranges()`` gives the latest range of
    every transducer (m, NaN = no echo)."""

    def __init__(
        self,
        ranges: Callable[[], np.ndarray],
        *,
        base_id: int = DEFAULT_BASE_ID,
        bitrate: int = 1_000_000,
        resolution: Resolution = Resolution.CM_0_5,
        transducers: Sequence[int] | None = None,
        params: ParameterSet | None = None,
        analog_counts: tuple[int, int, int, int] = (2048, 1024, 3072, 4095),
    ) -> None:
        self.codec = UsBoardCodec(base_id)
        self.ranges = ranges
        self.resolution = Resolution(resolution)
        self.transducers = tuple(range(SENSOR_COUNT) if transducers is None else transducers)
        self.params = params or default_parameters(base_id, bitrate)
        self.eeprom = self.params
        self.analog_counts = analog_counts
        #: Channels fire from power-up until the host says otherwise.
        self.active_mask = (1 << SENSOR_COUNT) - 1
        self.answer_connect = True
        self.wrong_ack_sum = False
        self._pending: dict[bool, dict[int, ParasetChunk]] = {False: {}, True: {}}
        self.counts = BoardCounts()

    def handle(self, frame: Frame) -> list[Frame]:
        """The replies to one frame seen on the bus (none for frames not addressed to it)."""
        if frame.arbitration_id != self.codec.base_id:
            self.counts.foreign_frames += 1
            return []
        try:
            command = self.codec.decode_command(frame)
        except CanSonarError:
            self.counts.bad_commands += 1
            return []
        self.counts.commands += 1
        replies = self._answer(command)
        self.counts.replies += len(replies)
        return replies

    def _answer(self, command: object) -> list[Frame]:
        codec = self.codec
        match command:
            case Connect():
                if not self.answer_connect:
                    self.counts.connects_ignored += 1
                    return []
                return [codec.encode_reply(ConnectReply())]
            case SetChannelActive(mask=mask):
                self.active_mask = mask
                return []
            case GetData(groups=groups):
                return [codec.encode_reply(self.group_data(g)) for g in groups]
            case GetLegacyData(bank=bank):
                return [codec.encode_reply(self._legacy(2 * bank + b)) for b in range(2)]
            case WriteParaset(chunk=chunk, eeprom=eeprom):
                return [codec.encode_reply(self._store(chunk, eeprom))]
            case ReadParaset():
                return codec.paraset_reply(self.params)
            case GetAnalogIn():
                return [codec.encode_reply(AnalogIn(self.analog_counts))]
        return []

    # ------------------------------------------------------------------ readings
    def readings(self) -> list[Reading]:
        """The board's current reading of each of its 16 channels."""
        ranges = np.asarray(self.ranges(), dtype=float)
        per_metre = self.resolution.counts_per_metre
        out = []
        for k in range(SENSOR_COUNT):
            t = self.transducers[k] if k < len(self.transducers) else -1
            if not (self.active_mask >> k & 1) or not 0 <= t < len(ranges):
                out.append(Reading(ReadingStatus.INVALID))
                continue
            out.append(_reading(float(ranges[t]), per_metre, _MAX_COUNTS))
        return out

    def group_data(self, group: int) -> GroupData:
        readings = self.readings()[SENSORS_PER_GROUP * group : SENSORS_PER_GROUP * (group + 1)]
        return GroupData(group, self.resolution, tuple(readings))

    def _legacy(self, block: int) -> LegacyData:
        ranges = np.asarray(self.ranges(), dtype=float)
        readings = []
        for k in range(SENSORS_PER_GROUP * block, SENSORS_PER_GROUP * (block + 1)):
            t = self.transducers[k] if k < len(self.transducers) else -1
            if not (self.active_mask >> k & 1) or not 0 <= t < len(ranges):
                readings.append(Reading(ReadingStatus.INVALID))
            else:
                r = float(ranges[t])
                readings.append(_reading(r, _LEGACY_COUNTS_PER_METRE, _LEGACY_MAX_COUNTS))
        return LegacyData(block, tuple(readings))

    # ------------------------------------------------------------------ parameter set
    def _store(self, chunk: ParasetChunk, eeprom: bool) -> WriteAck:
        """Keep the latest frame of each index (a host resends frames whose acknowledgement it
        lost); the acknowledgement of frame 8 carries the sum of the nine kept, and if all nine
        are there the set takes effect."""
        pending = self._pending[eeprom]
        pending[chunk.index] = chunk
        if chunk.index != PARASET_FRAME_COUNT - 1:
            return WriteAck(chunk.index, eeprom=eeprom)
        total = paraset_byte_sum(pending.values())
        if self.wrong_ack_sum:
            total = (total + 1) & 0xFFFF
        elif len(pending) == PARASET_FRAME_COUNT:
            try:
                params = paraset_from_chunks(pending.values())
            except CanSonarError:
                params = None
            if params is not None:
                self.params = params
                if eeprom:
                    self.eeprom = params
                self.counts.parameter_sets_written += 1
        return WriteAck(chunk.index, eeprom=eeprom, byte_sum=total)


def _reading(r: float, per_metre: int, max_counts: int) -> Reading:
    if math.isnan(r):
        return Reading(ReadingStatus.NO_ECHO)
    counts = round(r * per_metre)
    if counts < _FIRST_DISTANCE_COUNT:
        return Reading(ReadingStatus.TOO_CLOSE)
    if counts > max_counts:
        return Reading(ReadingStatus.NO_ECHO)  # beyond what the frame can carry
    return Reading.ok(counts / per_metre)


class Link(Protocol):
    path: str

    def fileno(self) -> int: ...
    def receive(self) -> list[Frame]: ...
    def send(self, frame: Frame) -> None: ...
    def send_bus_error(self) -> None: ...
    def close(self) -> None: ...


@dataclass
class CanSonarDevice:
    """A board on a link, with faults: an ``EmulatedDevice`` for ``EmulatorHost``."""

    board: UsBoardEmulator
    link: Link
    interface: str
    faults: BoardFaults = field(default_factory=BoardFaults)
    seed: int = 0
    bitrate: int = 1_000_000

    def __post_init__(self) -> None:
        self.injector = FaultInjector(self.faults, self.board.codec, self.seed)
        self.board.wrong_ack_sum = self.faults.wrong_ack_sum
        #: Set to stop answering CONNECT now, whatever the configured faults say (tests).
        self.heartbeat_stopped = False

    @property
    def channel(self) -> str:
        """The slave path of the pty, or the virtual channel's name."""
        return self.link.path

    def backend_options(self) -> dict[str, Any]:
        """A ``can-sonar`` backend configuration that reaches this board."""
        options: dict[str, Any] = {
            "backend": "can-sonar",
            "interface": self.interface,
            "channel": self.channel,
            "bitrate": self.bitrate,
            "base_id": f"0x{self.board.codec.base_id:03X}",
        }
        if self.interface == "slcan":
            options["open_delay_s"] = 0
        return options

    # ------------------------------------------------------------------ EmulatedDevice
    def fileno(self) -> int:
        return self.link.fileno()

    def service(self, now_s: float) -> None:
        self.tick(now_s)
        for frame in self.link.receive():
            for reply in self.board.handle(frame):
                self._emit(reply)

    def tick(self, now_s: float) -> None:
        stopped = self.heartbeat_stopped or self.injector.heartbeat_stopped(now_s)
        self.board.answer_connect = not stopped

    def close(self) -> None:
        self.link.close()

    def _emit(self, reply: Frame) -> None:
        out = self.injector.outgoing(reply)
        if isinstance(out, BusError):
            self.link.send_bus_error()
        elif out is not None:
            self.link.send(out)


def robot_ranges(robot: SimRobot) -> Callable[[], np.ndarray]:
    """The latest range of every transducer of the simulated ring."""
    return lambda: robot.ring.ranges


def make_device(
    robot: SimRobot | None,
    *,
    slcan_pty: bool = True,
    virtual_channel: str | None = None,
    base_id: int = DEFAULT_BASE_ID,
    bitrate: int = 1_000_000,
    resolution: Resolution = Resolution.CM_0_5,
    faults: BoardFaults | None = None,
    seed: int = 0,
    ranges: Callable[[], np.ndarray] | None = None,
) -> CanSonarDevice:
    """A board firing ``robot``'s ring (or ``ranges``) on an SLCAN pty or a virtual channel."""
    if ranges is None:
        if robot is None:
            raise ValueError("make_device needs a robot or a ranges source")
        ranges = robot_ranges(robot)
    board = UsBoardEmulator(ranges, base_id=base_id, bitrate=bitrate, resolution=resolution)
    link: Link
    if virtual_channel is not None:
        link, interface = VirtualCanChannel(virtual_channel), "virtual"
    elif slcan_pty:
        link, interface = SlcanPty(bitrate), "slcan"
    else:
        raise ValueError("choose an SLCAN pseudo-terminal or a virtual channel")
    return CanSonarDevice(board, link, interface, faults or BoardFaults(), seed, bitrate)

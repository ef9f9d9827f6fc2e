"""The CAN ultrasonic board (USBoard style) as a hal ``SonarRing``: ``can-sonar``.

Configuration (``create_backend({"backend": "can-sonar", ...})`` or
``can-sonar://INTERFACE:CHANNEL?option=value``):

- ``interface`` / ``channel`` (or ``target`` = ``INTERFACE:CHANNEL``): any python-can interface
  (socketcan can0, slcan /dev/ttyACM0, pcan PCAN_USBBUS1, virtual NAME); default socketcan can0;
- ``bitrate`` (bit/s, one the board knows; 1000000), ``base_id`` (0x400; an int or "0x..." );
- ``open_delay_s``: slcan only, the wait after opening the port (python-can's 2 s if unset;
  0 for an emulator's pseudo-terminal);
- ``channels``, ``angles_deg``, ``radius_m``: the ring layout (see ``layout``);
- ``min_range_m`` (0.15), ``max_range_m`` (6.5), ``beam_deg`` (12.5, half beam): the sensor;
- ``poll_s`` (0.1): how often data is requested; ``max_age_s`` (1.0): older readings are NaN;
  a ring constructed with ``poll_s=math.inf`` asks once at configure and then only when
  ``refresh()`` is called (a lockstep run, whose readings must be taken after each step);
- ``heartbeat_s`` (1.0), ``heartbeat_misses`` (3): the board is lost after that many CONNECT
  replies missed in a row; ``reply_timeout_s`` (0.5): how long configure waits for a reply
  before asking again (5 times, keeping what came, since frames get lost);
- ``write_params`` (none | ram | eeprom): write the parameter set at configure, each frame
  acknowledged and the final byte sum checked, then (with ``read_params``) read back and
  compared; ``update_interval_s`` (0.1), ``fire_interval_s`` (0.02), ``cross_echo`` (false),
  ``warning_m`` (0.5), ``alarm_m`` (0.3) are what is written;
- ``read_params`` (true): read the board's parameter set at configure (``board_parameters``).

Lifecycle: the constructor touches nothing. ``configure`` opens the bus, waits for a CONNECT
reply, activates the mapped channels, handles the parameter set, then starts one background
thread that sends CONNECT every ``heartbeat_s`` and GET_DATA every ``poll_s`` and decodes what
comes back; configure returns once every requested group has reported. ``close`` stops the
thread and releases the bus.

Time: ``clock`` is the host's monotonic clock unless another is passed to the constructor; the
heartbeat runs on it and every reading is stamped with the arrival of its frame (the board's
frames carry no time), never re-stamped later (see ``readings``).

Faults: once the board has missed ``heartbeat_misses`` CONNECT replies, ``scan`` raises
``DeviceFaultError`` naming the board (base identifier and bus), and keeps raising until the
backend is closed, so whoever drives the robot stops it. A bus that fails under the driver
raises ``LinkLostError`` the same way. Corrupt and foreign frames are skipped and counted
(``stats``), never used; see ``link`` for the policy.
"""

from __future__ import annotations

import math
import threading
import time
from collections.abc import Callable, Mapping
from typing import Any

import numpy as np

from drivers.can_sonar.codec import (
    BITRATE_CODES,
    DEFAULT_BASE_ID,
    GROUP_COUNT,
    MAX_BASE_ID,
    PARASET_FRAME_COUNT,
    SENSOR_COUNT,
    CanSonarError,
    ConnectReply,
    GroupData,
    ParameterSet,
    ParasetChunk,
    ParasetData,
    Reply,
    UsBoardCodec,
    WriteAck,
    WriteParaset,
    paraset_byte_sum,
    paraset_from_chunks,
    paraset_to_chunks,
)
from drivers.can_sonar.heartbeat import Heartbeat
from drivers.can_sonar.layout import RingLayout, layout_from_values
from drivers.can_sonar.link import BoardLink, BusSettings, LinkStats, open_bus
from drivers.can_sonar.readings import ReadingTable
from hal.clock import Clock, MonotonicClock
from hal.config import Options
from hal.errors import (
    ConfigurationError,
    DeviceFaultError,
    DeviceTimeoutError,
    HalError,
    LinkLostError,
    ProtocolError,
)
from hal.interfaces import SonarRing
from hal.types import SonarScan

#: Longest single wait of the background thread, so ``close`` never waits long for it.
_MAX_WAIT_S = 0.05
#: Requests of the configure sequence are repeated this often before giving up (frames get lost).
_ATTEMPTS = 5


class CanSonarRing(SonarRing):
    """A sonar ring read from a CAN ultrasonic board."""

    backend_name = "can-sonar"

    def __init__(
        self,
        bus: BusSettings,
        *,
        base_id: int = DEFAULT_BASE_ID,
        layout: RingLayout | None = None,
        min_range_m: float = 0.15,
        max_range_m: float = 6.5,
        half_beam_rad: float = math.radians(12.5),
        poll_s: float = 0.1,
        max_age_s: float = 1.0,
        heartbeat_s: float = 1.0,
        heartbeat_misses: int = 3,
        reply_timeout_s: float = 0.5,
        write_params: ParameterSet | None = None,
        write_to_eeprom: bool = False,
        read_params: bool = True,
        clock: Clock | None = None,
        bus_factory: Callable[[BusSettings], Any] = open_bus,
    ) -> None:
        super().__init__()
        self.bus_settings = bus
        self.codec = UsBoardCodec(base_id)
        self.layout = layout or RingLayout.nomad_ring()
        self.min_range_m = min_range_m
        self.max_range_m = max_range_m
        self.half_beam_rad = half_beam_rad
        self.poll_s = poll_s
        self.max_age_s = max_age_s
        self.heartbeat_s = heartbeat_s
        self.heartbeat_misses = heartbeat_misses
        self.reply_timeout_s = reply_timeout_s
        self.write_params = write_params
        self.write_to_eeprom = write_to_eeprom
        self.read_params = read_params
        self._clock: Clock = clock or MonotonicClock()
        self._bus_factory = bus_factory
        #: The parameter set read from the board at configure (None if not read).
        self.board_parameters: ParameterSet | None = None
        self.board_name = f"CAN sonar board at 0x{base_id:03X} on {bus.describe()}"
        self._link: BoardLink | None = None
        self._heartbeat = Heartbeat(heartbeat_s, heartbeat_misses)
        self._table = self._new_table()
        self._arrivals = dict.fromkeys(range(GROUP_COUNT), 0)  # group frames received
        self._data_lock = threading.Lock()
        self._data_ready = threading.Condition(self._data_lock)
        self._fault: HalError | None = None
        self._stop_event = threading.Event()
        self._thread: threading.Thread | None = None
        n = len(self.layout)
        angles = np.asarray(self.layout.angles_rad, dtype=float)
        radii = np.asarray(self.layout.radii_m, dtype=float)
        self._x = radii * np.cos(angles)
        self._y = radii * np.sin(angles)
        self._yaw = np.angle(np.exp(1j * angles))
        assert len(self._x) == n

    def _new_table(self) -> ReadingTable:
        return ReadingTable(
            self.layout,
            min_range_m=self.min_range_m,
            max_range_m=self.max_range_m,
            max_age_s=self.max_age_s,
        )

    # ------------------------------------------------------------------ configuration
    @classmethod
    def from_config(cls, options: Mapping[str, Any]) -> CanSonarRing:
        raw = dict(options)
        # List-valued layout options are read here: Options reads scalars only.
        layout = layout_from_values(
            raw.pop("channels", None), raw.pop("angles_deg", None), raw.pop("radius_m", None)
        )
        base_raw = raw.pop("base_id", DEFAULT_BASE_ID)
        opts = Options("can-sonar", raw)
        target = opts.str("target", "")
        if target:
            interface, sep, channel = target.partition(":")
            if not sep or not interface or not channel:
                raise ConfigurationError(
                    f"can-sonar: target must look like INTERFACE:CHANNEL, got {target!r}"
                )
        else:
            interface, channel = "socketcan", "can0"
        interface = opts.str("interface", interface)
        channel = opts.str("channel", channel)
        _check_interface(interface)
        bitrate = opts.int("bitrate", 1_000_000)
        if bitrate not in BITRATE_CODES:
            raise ConfigurationError(
                f"can-sonar: option 'bitrate' must be one the board knows"
                f" ({', '.join(str(b) for b in BITRATE_CODES)}), got {bitrate}"
            )
        base_id = _base_id(base_raw)
        open_delay = (
            opts.float("open_delay_s", 0.0, lo=0.0, hi=10.0) if "open_delay_s" in raw else None
        )
        poll_s = opts.float("poll_s", 0.1, lo=0.005, hi=5.0)
        heartbeat_s = opts.float("heartbeat_s", 1.0, lo=0.02, hi=10.0)
        kwargs: dict[str, Any] = dict(
            base_id=base_id,
            layout=layout,
            min_range_m=opts.float("min_range_m", 0.15, lo=0.0, hi=1.0),
            max_range_m=opts.float("max_range_m", 6.5, lo=0.5, hi=40.0),
            half_beam_rad=math.radians(opts.float("beam_deg", 12.5, lo=1.0, hi=60.0)),
            poll_s=poll_s,
            max_age_s=opts.float("max_age_s", 1.0, lo=poll_s, hi=60.0),
            heartbeat_s=heartbeat_s,
            heartbeat_misses=opts.int("heartbeat_misses", 3, lo=1, hi=100),
            reply_timeout_s=opts.float("reply_timeout_s", 0.5, lo=0.01, hi=60.0),
            read_params=opts.bool("read_params", True),
        )
        mode = opts.choice("write_params", ("none", "ram", "eeprom"), "none")
        params = ParameterSet(
            update_interval_s=opts.float("update_interval_s", 0.1, lo=0.05, hi=12.8),
            warning_distances_m=(opts.float("warning_m", 0.5, lo=0.0, hi=2.55),) * SENSOR_COUNT,
            alarm_distances_m=(opts.float("alarm_m", 0.3, lo=0.0, hi=2.55),) * SENSOR_COUNT,
            cross_echo=opts.bool("cross_echo", False),
            fire_intervals_s=(opts.float("fire_interval_s", 0.02, lo=0.01, hi=2.56),) * GROUP_COUNT,
            bitrate=bitrate,
            base_id=base_id,
        )
        opts.finish()
        if mode != "none":
            try:
                paraset_to_chunks(params)  # grid and range checks now, not at configure
            except CanSonarError as exc:
                raise ConfigurationError(f"can-sonar: parameter set: {exc}") from None
        if kwargs["min_range_m"] >= kwargs["max_range_m"]:
            raise ConfigurationError("can-sonar: min_range_m must be below max_range_m")
        settings = BusSettings(interface, channel, bitrate, open_delay)
        return cls(
            settings,
            write_params=params if mode != "none" else None,
            write_to_eeprom=mode == "eeprom",
            **kwargs,
        )

    # ------------------------------------------------------------------ Backend
    @property
    def clock(self) -> Clock:
        return self._clock

    @property
    def n_transducers(self) -> int:
        return len(self.layout)

    @property
    def stats(self) -> LinkStats:
        """Frame counters of the current (or last) connection."""
        if self._link is None:
            return LinkStats()
        self._link.stats.heartbeats_missed = self._heartbeat.total_missed
        return self._link.stats

    def _on_configure(self) -> None:
        self._fault = None
        self._heartbeat = Heartbeat(self.heartbeat_s, self.heartbeat_misses)
        self._table = self._new_table()
        bus = self._bus_factory(self.bus_settings)
        self._link = BoardLink(bus, self.codec, self._clock, self.bus_settings.describe())
        self._connect()
        self._link.send(self.codec.set_channels_active(self.layout.active_mask))
        if self.write_params is not None:
            self._write_parameters(self.write_params)
        if self.read_params:
            self.board_parameters = self._read_parameters()
            if self.write_params is not None and self.board_parameters != self.write_params:
                raise ProtocolError(
                    f"{self.board_name}: the parameter set read back differs from the one"
                    f" written and acknowledged: {self.board_parameters} != {self.write_params}"
                )
        self._stop_event.clear()
        self._thread = threading.Thread(
            target=self._run, name=f"can-sonar 0x{self.codec.base_id:03X}", daemon=True
        )
        self._thread.start()
        self._await_first_data()

    def _on_close(self) -> None:
        self._stop_event.set()
        if self._thread is not None:
            self._thread.join(timeout=5.0)
            self._thread = None
        if self._link is not None:
            self._link.close()

    # ------------------------------------------------------------------ SonarRing
    def _scan(self) -> SonarScan:
        fault = self._fault
        if fault is not None:
            raise type(fault)(str(fault))
        with self._data_lock:
            ranges, stamps = self._table.snapshot(self._clock.now())
        return SonarScan(
            ranges_m=ranges,
            x_m=self._x.copy(),
            y_m=self._y.copy(),
            yaw_rad=self._yaw.copy(),
            stamps_s=stamps,
            min_range_m=self.min_range_m,
            max_range_m=self.max_range_m,
            half_beam_rad=self.half_beam_rad,
        )

    def refresh(self, timeout_s: float = 2.0) -> None:
        """Ask the board for every group now and return once each has answered.

        For a caller that lets simulated time pass in steps: with ``poll_s=math.inf`` no other
        request is in flight, so every reading the next ``scan`` returns was taken after the
        step. ``timeout_s`` is in host seconds (a stepped clock stands still while this waits).
        Raises the ring's fault if it has one, ``DeviceTimeoutError`` if a group stays silent.
        """
        with self._lock:
            self._require_active("refresh the readings")
            link = self._link_or_fail()
            groups = self.layout.groups
            with self._data_ready:
                before = {g: self._arrivals[g] for g in groups}
            link.send(self.codec.get_data(groups))
            deadline = time.monotonic() + timeout_s
            with self._data_ready:
                while True:
                    if self._fault is not None:
                        raise type(self._fault)(str(self._fault))
                    silent = [g for g in groups if self._arrivals[g] == before[g]]
                    if not silent:
                        return
                    left = deadline - time.monotonic()
                    if left <= 0:
                        raise DeviceTimeoutError(
                            f"{self.board_name}: no data from groups {silent} within"
                            f" {timeout_s:g} s of asking"
                        )
                    self._data_ready.wait(min(left, _MAX_WAIT_S))

    # ------------------------------------------------------------------ configure steps
    def _link_or_fail(self) -> BoardLink:
        if self._link is None:  # pragma: no cover - only reachable by misuse of internals
            raise LinkLostError(f"{self.board_name}: the bus is not open")
        return self._link

    def _take(self, reply: Reply, stamp: float) -> None:
        """Bookkeeping every received reply gets, whoever waits for it."""
        if isinstance(reply, ConnectReply):
            self._heartbeat.replied(stamp)
        elif isinstance(reply, GroupData):
            with self._data_ready:
                self._table.update(reply, stamp)
                self._arrivals[reply.group] = self._arrivals.get(reply.group, 0) + 1
                self._data_ready.notify_all()

    def _await(
        self, want: Callable[[Reply], bool], timeout_s: float, resend: Callable[[], None] | None
    ) -> Reply | None:
        """Receive until a reply ``want`` accepts arrives; ``resend`` every heartbeat period."""
        link = self._link_or_fail()
        deadline = self._clock.now() + timeout_s
        next_send = self._clock.now() + self.heartbeat_s
        while True:
            now = self._clock.now()
            if now >= deadline:
                return None
            if resend is not None and now >= next_send:
                resend()
                next_send = now + self.heartbeat_s
            got = link.receive(min(deadline - now, _MAX_WAIT_S))
            if got is None:
                continue
            reply, stamp = got
            self._take(reply, stamp)
            if want(reply):
                return reply

    def _connect(self) -> None:
        link = self._link_or_fail()

        def send_connect() -> None:
            link.send(self.codec.connect())
            self._heartbeat.sent(self._clock.now())

        send_connect()
        wait = self.heartbeat_s * self.heartbeat_misses
        if self._await(lambda r: isinstance(r, ConnectReply), wait, send_connect) is None:
            raise DeviceTimeoutError(
                f"{self.board_name}: no reply to CONNECT within {wait:g} s (is the board powered,"
                f" on this bus, at bitrate {self.bus_settings.bitrate} and this base identifier?)"
            )

    def _write_parameters(self, params: ParameterSet) -> None:
        """Nine frames, each sent until acknowledged; the final acknowledgement's byte sum must
        match what was sent. A board keeps the latest frame of each index, so resending a frame
        whose acknowledgement was lost is harmless."""
        link = self._link_or_fail()
        chunks = paraset_to_chunks(params)
        where = "EEPROM" if self.write_to_eeprom else "RAM"
        for chunk in chunks:
            frame = self.codec.encode_command(WriteParaset(chunk, self.write_to_eeprom))

            def acked(reply: Reply, index: int = chunk.index) -> bool:
                # Late duplicates of earlier acknowledgements (after a resend) are not news.
                return isinstance(reply, WriteAck) and reply.index >= index

            for _ in range(_ATTEMPTS):
                link.send(frame)
                ack = self._await(acked, self.reply_timeout_s, None)
                if ack is not None:
                    break
            else:
                raise DeviceTimeoutError(
                    f"{self.board_name}: parameter frame {chunk.index} (write to {where}) not"
                    f" acknowledged after {_ATTEMPTS} tries of {self.reply_timeout_s:g} s"
                )
            assert isinstance(ack, WriteAck)
            if ack.index != chunk.index or ack.eeprom != self.write_to_eeprom:
                kind = "EEPROM" if ack.eeprom else "RAM"
                raise ProtocolError(
                    f"{self.board_name}: wrote parameter frame {chunk.index} to {where} but the"
                    f" board acknowledged frame {ack.index} to {kind}; parameter set refused"
                )
            if ack.byte_sum is not None:
                expected = paraset_byte_sum(chunks)
                if ack.byte_sum != expected:
                    raise ProtocolError(
                        f"{self.board_name}: the board acknowledged the parameter set with byte"
                        f" sum 0x{ack.byte_sum:04X}, but 0x{expected:04X} was sent; parameter"
                        f" set refused"
                    )

    def _read_parameters(self) -> ParameterSet:
        link = self._link_or_fail()
        chunks: dict[int, ParasetChunk] = {}

        def want(reply: Reply) -> bool:
            if isinstance(reply, ParasetData):
                chunks[reply.chunk.index] = reply.chunk
            return len(chunks) == PARASET_FRAME_COUNT

        # Frames lost on the way are asked for again; those that came are kept.
        for _ in range(_ATTEMPTS):
            link.send(self.codec.read_paraset())
            if self._await(want, self.reply_timeout_s, None) is not None:
                break
        else:
            missing = sorted(set(range(PARASET_FRAME_COUNT)) - chunks.keys())
            raise DeviceTimeoutError(
                f"{self.board_name}: parameter set incomplete after {_ATTEMPTS} requests"
                f" (frames {missing} missing)"
            )
        try:
            return paraset_from_chunks(chunks.values())
        except CanSonarError as exc:
            raise ProtocolError(f"{self.board_name}: parameter set does not parse: {exc}") from None

    def _await_first_data(self) -> None:
        groups = self.layout.groups
        # Polled on demand there is one request to wait for, not one per period.
        period = self.poll_s if math.isfinite(self.poll_s) else self.reply_timeout_s
        wait = _ATTEMPTS * max(self.reply_timeout_s, period)
        deadline = self._clock.now() + wait
        with self._data_ready:
            while not self._table.has_groups(groups):
                if self._fault is not None:
                    raise type(self._fault)(str(self._fault))
                left = deadline - self._clock.now()
                if left <= 0:
                    seen = sorted(self._table.groups_seen)
                    raise DeviceTimeoutError(
                        f"{self.board_name}: no data from groups"
                        f" {sorted(set(groups) - set(seen))} within {wait:g} s of asking"
                    )
                self._data_ready.wait(min(left, _MAX_WAIT_S))

    # ------------------------------------------------------------------ the background thread
    def _run(self) -> None:
        link = self._link_or_fail()
        request = self.codec.get_data(self.layout.groups)
        next_poll = self._clock.now()
        try:
            while not self._stop_event.is_set():
                now = self._clock.now()
                if self._heartbeat.due(now):
                    link.send(self.codec.connect())
                    self._heartbeat.sent(now)
                    if self._heartbeat.lost:
                        self._fail(
                            DeviceFaultError(
                                f"{self.board_name} lost: {self._heartbeat.missed} CONNECT"
                                f" replies missed in a row (heartbeat every"
                                f" {self.heartbeat_s:g} s)"
                            )
                        )
                        return
                if now >= next_poll:
                    link.send(request)
                    # Regular polls, but no burst to catch up after a stall.
                    next_poll = max(next_poll + self.poll_s, now)
                wait = min(self._heartbeat.next_due_s, next_poll) - self._clock.now()
                got = link.receive(min(max(wait, 0.001), _MAX_WAIT_S))
                if got is not None:
                    self._take(*got)
        except HalError as exc:
            self._fail(exc)

    def _fail(self, error: HalError) -> None:
        with self._data_ready:
            self._fault = error
            self._data_ready.notify_all()


def _check_interface(interface: str) -> None:
    import can

    if interface not in can.VALID_INTERFACES:
        raise ConfigurationError(
            f"can-sonar: unknown CAN interface {interface!r}"
            f" (python-can knows: {', '.join(sorted(can.VALID_INTERFACES))})"
        )


def _base_id(value: Any) -> int:
    try:
        if isinstance(value, bool):
            raise ValueError
        base = int(value, 0) if isinstance(value, str) else int(value)
        if isinstance(value, float) and not value.is_integer():
            raise ValueError
    except (TypeError, ValueError):
        raise ConfigurationError(
            f"can-sonar: option 'base_id' must be an integer such as 0x400, got {value!r}"
        ) from None
    if not 0 <= base <= MAX_BASE_ID:
        raise ConfigurationError(
            f"can-sonar: option 'base_id' must be 0x000-0x{MAX_BASE_ID:03X} so that every reply"
            f" identifier is a standard one, got 0x{base:X}"
        )
    return base

"""The Nomad 200 behind the hal: ``nomad200:///dev/ttyUSB0`` (options in ``settings``).

One state mask serves every read: all 16 sonars (with their "pos" attachments if ``sonar_pos``),
the bumpers, x, y, steering, turret and the three velocities. Every state reply the robot sends
(to ``gs``, ``vm``, ``st``, the configuration requests, a lockstep step) refreshes one cached
state; ``scan``, ``odometry`` and ``status`` read that cache while it is younger than
``max_state_age_s`` and otherwise poll with one ``gs``. A control cycle (read, think, command)
therefore costs two round trips: one ``gs``, one ``vm``; in lockstep the step reply carries the
state, so the ``gs`` goes too.

Freshness: a failed exchange empties the cache, so a read after a fault polls again or raises;
it never hands back the last good reading. Every stamp is the robot's own (see ``clock``).

Units are converted here and only here: 1/10 inch and 1/10 degree (and per second) to SI, sonar
inches (from the transducer) to metres; 255 is "no echo".

Lifecycle: ``configure`` opens the port and sends ``ct``, ``conf_sn``, ``conf_tm``, ``sp``,
``ac`` and a ``st``; ``deactivate`` sends ``st``; ``close`` sends ``st`` and closes the port.
The constructor touches nothing.
"""

from __future__ import annotations

import contextlib
import math
import time
from collections.abc import Callable, Mapping
from typing import Any

import numpy as np
import serial

from drivers.nomad200 import lockstep
from drivers.nomad200.clock import ControllerClock
from drivers.nomad200.codec import (
    DEFAULT_MAX_LEN,
    Ac,
    Command,
    ConfSn,
    ConfTm,
    Ct,
    Gs,
    RawReply,
    Reply,
    Sp,
    Special,
    St,
    State,
    StateLayout,
    StateMask,
    StateReply,
    Vm,
    Ws,
    Zr,
)
from drivers.nomad200.errors import ProtocolError as CodecError
from drivers.nomad200.integers import S16_MAX
from drivers.nomad200.link import Link
from drivers.nomad200.odometry import OdometryTracker
from drivers.nomad200.opcodes import STATE_REPLY_OPCODES, Opcode
from drivers.nomad200.settings import NAME, Settings
from drivers.nomad200.state import SENSORS
from drivers.nomad200.units import (
    inch_to_m,
    m_to_tenth_inch,
    rad_to_tenth_deg,
    tenth_deg_to_rad,
)
from hal.errors import CommunicationError, ProtocolError
from hal.interfaces import Drive, DriveLimits, Encoders, SonarRing
from hal.lifecycle import State as LifecycleState
from hal.types import DriveStatus, Odometry, SonarScan, Twist

NO_ECHO = 255
#: The reference's bound on zeroing the robot.
ZR_TIMEOUT_S = 120.0
_ANGLES = np.arange(SENSORS) * (2.0 * math.pi / SENSORS)
#: Requests that mean the same when received twice (safe to retransmit). PR moves relative to
#: wherever the robot is, so it is sent once; a lockstep step names an absolute time.
_NOT_IDEMPOTENT = frozenset({Opcode.PR, Opcode.TK})


def _s16(value: int) -> int:
    return max(-S16_MAX, min(S16_MAX, value))


def _u16(value: int) -> int:
    return max(0, min(0xFFFF, value))


class Nomad200Backend(Drive, Encoders, SonarRing):
    """A Nomad 200 base and sonar ring on a serial line (or a socket, or an emulator's pty)."""

    backend_name = NAME

    def __init__(
        self,
        settings: Settings,
        *,
        opener: Callable[..., serial.SerialBase] = serial.serial_for_url,
        monotonic: Callable[[], float] = time.monotonic,
    ) -> None:
        super().__init__()
        self.settings = settings
        self.backend_name = f"{NAME} {settings.port}"
        everything = frozenset(range(SENSORS))
        self.mask = StateMask(
            sonar=everything,
            bumper=True,
            x=True,
            y=True,
            steer=True,
            turret=True,
            vel_trans=True,
            vel_steer=True,
            vel_turret=True,
            pos_sonar=settings.sonar_pos,
        )
        self._layout = StateLayout(self.mask)
        self._monotonic = monotonic
        self.link = Link(
            settings.port,
            settings.baud,
            reply_timeout_s=settings.reply_timeout_s,
            retries=settings.retries,
            reconnect_timeout_s=settings.reconnect_timeout_s,
            reconnect_backoff_s=settings.reconnect_backoff_s,
            name=NAME,
            opener=opener,
            monotonic=monotonic,
        )
        self.link.on_reconnect = self._after_reconnect
        self._clock = ControllerClock(
            lockstep=settings.lockstep,
            time_scale=settings.time_scale,
            step=self._lockstep_step,
            monotonic=monotonic,
        )
        self._odometry_tracker = OdometryTracker()
        self._cached: State | None = None
        self._cached_s = 0.0  # controller time of the cached state
        self._cached_heard = 0.0  # host time it arrived
        self._commanded_v = 0.0
        self._closing = False
        #: A stop that failed while closing (the link was gone); the robot's watchdog stops it.
        self.close_error: CommunicationError | None = None

    @classmethod
    def from_config(cls, options: Mapping[str, Any]) -> Nomad200Backend:
        return cls(Settings.from_options(options))

    # ------------------------------------------------------------------ Backend
    @property
    def clock(self) -> ControllerClock:
        """The robot's controller clock (see ``drivers.nomad200.clock``)."""
        return self._clock

    @property
    def limits(self) -> DriveLimits:
        return self.settings.limits

    @property
    def n_transducers(self) -> int:
        return SENSORS

    def _on_configure(self) -> None:
        self.link.open()
        self._configure_robot()

    def _configure_robot(self) -> None:
        s, lim = self.settings, self.settings.limits
        self._send(Ct(self.mask))
        self._send(ConfSn(s.sonar_rate if s.sonar_order else 0, s.sonar_order))
        self._send(ConfTm(s.motion_timeout_s))
        self._send(
            Sp(
                _u16(m_to_tenth_inch(lim.v_mps)),
                _u16(rad_to_tenth_deg(lim.steer_radps)),
                _u16(rad_to_tenth_deg(lim.turret_radps)),
            )
        )
        self._send(
            Ac(
                _u16(m_to_tenth_inch(lim.accel_mps2)),
                _u16(rad_to_tenth_deg(lim.steer_accel_radps2)),
                _u16(rad_to_tenth_deg(lim.turret_accel_radps2)),
            )
        )
        # Nothing moves after configure, even if an earlier session left the robot driving.
        self._send(St())
        self._commanded_v = 0.0

    def _after_reconnect(self) -> None:
        # The robot may have been reset while the line was down: its mask and settings go
        # again, and its ``st`` is the stop the link owes the robot when it comes back.
        self._cached = None
        self._configure_robot()

    def _on_close(self) -> None:
        try:
            if self.link.is_open:
                self._send(St(), reconnect=False)
        except CommunicationError as exc:
            self.close_error = exc
        finally:
            self.link.close()

    def close(self) -> None:
        """Stop and release the port. A link already gone cannot take the stop; that failure
        is kept in ``close_error`` rather than raised, since the robot's own motion timeout
        (``conf_tm``) stops it and the fault was reported when it happened."""
        self._closing = True
        try:
            super().close()
        except CommunicationError as exc:
            self.close_error = exc

    # ------------------------------------------------------------------ requests
    def send(self, command: Command, *, timeout_s: float | None = None) -> Reply:
        """Send any request (``Dp``, ``Da``, ``Ws``, ``Zr``, ...) and return its reply.

        Motion requests need the backend active; state replies refresh the cached state.
        ``ws`` and ``zr`` wait as long as the robot may take to answer them (their own timeout
        plus a second; 120 s) unless ``timeout_s`` says otherwise.
        """
        with self._lock:
            self._require_open(f"send {command.name()}")
            if command.OPCODE in (Opcode.VM, Opcode.PR, Opcode.PA, Opcode.MV):
                self._require_active(f"send {command.name()}")
            if timeout_s is None and isinstance(command, Ws):
                timeout_s = command.timeout + 1.0 + self.settings.reply_timeout_s
            elif timeout_s is None and isinstance(command, Zr):
                timeout_s = ZR_TIMEOUT_S + self.settings.reply_timeout_s
            return self._send(command, timeout_s=timeout_s)

    def _send(
        self,
        command: Command,
        *,
        timeout_s: float | None = None,
        min_clock_ms: int | None = None,
        reconnect: bool | None = None,
        retries: int | None = None,
    ) -> Reply:
        floor = self._clock.last_ms if min_clock_ms is None else min_clock_ms
        try:
            reply = self.link.request(
                command,
                self.mask,
                idempotent=command.OPCODE not in _NOT_IDEMPOTENT,
                timeout_s=timeout_s,
                max_len=self._max_len(command),
                accept=lambda r: self._not_stale(r, floor),
                retries=retries,
                reconnect=not self._closing if reconnect is None else reconnect,
            )
            state = self._state_of(reply)
        except CommunicationError:
            self._cached = None  # nothing read before a fault counts as fresh after it
            if self.state is LifecycleState.ACTIVE and command.OPCODE != Opcode.ST:
                self._try_stop()
            raise
        if state is not None:
            self._take(state)
        return reply

    def _try_stop(self) -> None:
        """After a failed request: one quick ``st``, so a loop that stops reading the errors
        does not leave the robot driving on its last command."""
        with contextlib.suppress(CommunicationError):  # the link is down: conf_tm stops it
            self.link.request(St(), self.mask, retries=0, reconnect=False)
        self._commanded_v = 0.0

    def _max_len(self, command: Command) -> int:
        size = self._layout.size or DEFAULT_MAX_LEN
        if command.OPCODE in STATE_REPLY_OPCODES:
            return size + 2  # LEN counts TYPE and CHK too
        if isinstance(command, Special):
            return size + len(lockstep.MAGIC) + 2
        return DEFAULT_MAX_LEN

    def _state_of(self, reply: Reply) -> State | None:
        if isinstance(reply, StateReply):
            return reply.state
        if isinstance(reply, RawReply) and reply.opcode == Opcode.SPECIAL:
            try:
                return lockstep.parse_step_reply(reply, self.mask)
            except CodecError as exc:
                raise ProtocolError(f"{self.link.who}: malformed lockstep reply: {exc}") from exc
        return None

    def _not_stale(self, reply: Reply, floor_ms: int) -> bool:
        # Without sequence numbers, a reply's clock is the only way to tell a late answer to an
        # earlier request from the answer to this one.
        try:
            state = self._state_of(reply)
        except ProtocolError:
            return True  # let the caller report it
        return state is None or self._clock.unwrap(state.clock_ms) >= floor_ms

    def _take(self, state: State) -> None:
        self._cached_s = self._clock.observe(state.clock_ms)
        self._cached_heard = self._monotonic()
        self._cached = state
        self._odometry_tracker.update(state, self._cached_s)

    def _fresh_state(self) -> State:
        state = self._cached
        if state is not None and (
            self.settings.lockstep
            or self._monotonic() - self._cached_heard <= self.settings.max_state_age_s
        ):
            return state
        self._send(Gs())
        assert self._cached is not None
        return self._cached

    def _lockstep_step(self, seconds: float) -> None:
        with self._lock:
            self._require_open("let the emulator's time pass")
            start = self._clock.last_ms
            target = start + round(seconds * 1000.0)
            if target <= start:
                return
            timeout = self.settings.reply_timeout_s + seconds
            self._send(lockstep.step_request(target), timeout_s=timeout, min_clock_ms=target)

    # ------------------------------------------------------------------ Drive
    def _command(self, twist: Twist) -> None:
        self._send(
            Vm(
                _s16(m_to_tenth_inch(twist.v_mps)),
                _s16(rad_to_tenth_deg(twist.steer_radps)),
                _s16(rad_to_tenth_deg(twist.turret_radps)),
            )
        )
        self._commanded_v = twist.v_mps

    def _stop(self) -> None:
        self._send(St())
        self._commanded_v = 0.0

    def _status(self) -> DriveStatus:
        state = self._fresh_state()
        bumper = bool(state.bumper)
        # The protocol has no stall flag: a base pressed against its bumper that was told to
        # drive but does not move is stalled (the simulator's meaning too).
        stall = bumper and self._commanded_v != 0.0 and state.vel_trans == 0
        return DriveStatus(
            bumper=bumper,
            stall=stall,
            motors_on=bool(state.motor_status & 0b111),
            stamp_s=self._cached_s,
        )

    # ------------------------------------------------------------------ Encoders
    def _odometry(self) -> Odometry:
        self._fresh_state()
        pose = self._odometry_tracker.pose
        assert pose is not None
        return Odometry(
            x_m=pose.x_m,
            y_m=pose.y_m,
            heading_rad=pose.heading_rad,
            turret_rad=pose.turret_rad,
            stamp_s=pose.stamp_s,
            distance_m=pose.distance_m,
        )

    # ------------------------------------------------------------------ SonarRing
    def _scan(self) -> SonarScan:
        state = self._fresh_state()
        s = self.settings
        ranges = np.full(SENSORS, np.nan)
        relative = np.zeros(SENSORS)  # turret minus steering, when each transducer fired
        stamps = np.zeros(SENSORS)
        assert state.turret is not None and state.steer is not None
        for i in range(SENSORS):
            raw = state.sonar[i]
            if raw is not None and raw != NO_ECHO and raw <= s.max_range_in:
                ranges[i] = inch_to_m(max(raw, s.min_range_in))
            pos = state.sonar_pos[i]
            if pos is not None:
                relative[i] = tenth_deg_to_rad(pos.turret - pos.steer)
                stamps[i] = self._clock.seconds(pos.sense_time)
            else:
                # Without "pos" the firing time is unknown: the reading is stamped when the
                # robot reported it and posed with the turret as it is now.
                relative[i] = tenth_deg_to_rad(state.turret - state.steer)
                stamps[i] = self._cached_s
        yaw = np.angle(np.exp(1j * (relative + _ANGLES)))
        return SonarScan(
            ranges_m=ranges,
            x_m=s.ring_radius_m * np.cos(yaw),
            y_m=s.ring_radius_m * np.sin(yaw),
            yaw_rad=yaw,
            stamps_s=np.minimum(stamps, self._cached_s),
            min_range_m=inch_to_m(s.min_range_in),
            max_range_m=inch_to_m(s.max_range_in),
            half_beam_rad=s.half_beam_rad,
        )

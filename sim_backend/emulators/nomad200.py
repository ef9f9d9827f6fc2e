"""The Nomad 200 seen from the host: its serial protocol, served from the simulated robot.

``Nomad200Emulator`` is an ``EmulatedDevice`` for ``EmulatorHost``. It decodes requests with the
driver's own codec, acts on the ``SimRobot`` and answers laid out by the state mask the host set
with ``ct`` (at power-up the mask is empty: state replies carry only the tail).

Honoured: ``ct``; ``vm`` (capped by ``sp``); ``pr`` and ``pa`` (position moves at the ``sp``
speeds, braking at the ``ac`` accelerations); ``mv`` in its VM, PR, PA, LP, AC and SP modes;
``st``; ``lp`` (motors off); ``ws`` (answered when the axes stop or its timeout passes); ``zr``,
``dp`` and ``da`` (redefine the reported pose; the simulated wheels are not turned); ``conf_sn``
(firing order and rate; rate 0 switches the ring off); ``conf_tm`` (the robot stops when no
motion command comes in time, on simulated time); ``ac``; ``conf_cp`` (calibration answers
scores); ``tk`` (kept in ``spoken``); the ``get_*`` requests; the other ``conf_*`` and
``setup_ls`` are acknowledged. Torque modes of ``mv``, and user packets other than the lockstep
step, are answered NAK; frames that do not decode get no answer (the robot drains its input).

Values as the robot sends them: angles modulo a turn (0-3599); sonar in whole inches from the
transducer, 255 for no echo; IR 15 (nothing near: the simulator has no IR); the compass the true
heading; bumper bit 0 for the simulator's single ring. A sonar's "pos" attachment carries the
sensing time of that firing and a turret angle whose difference from the steering angle is the
turret's, relative to the steering, when the transducer fired (what a host needs to pose the
reading); its x, y and steering are those at the reply.

Time: in real-time mode the host steps the robot and ``tick`` keeps the controller's duties.
In lockstep mode simulated time passes only on a lockstep step request (``drivers.nomad200.
lockstep``: "run until controller time T", answered with the state then), on ``ws`` (until the
axes stop or its timeout) and nowhere else; the step is one ``robot.step`` unless a watchdog
deadline or a position move falls inside it, so a driver-driven run repeats an in-process one.
"""

from __future__ import annotations

import math
import time
from collections import Counter, deque
from collections.abc import Callable
from dataclasses import replace

from drivers.nomad200 import lockstep
from drivers.nomad200.codec import (
    Ac,
    BumperReply,
    Command,
    CompassCalibrationReply,
    CompassMode,
    CompassReply,
    ConfCp,
    ConfigurationReply,
    ConfSn,
    ConfTm,
    Ct,
    Da,
    Dp,
    FrameDecoder,
    IrReply,
    Mv,
    MvMode,
    NakReply,
    Opcode,
    Pa,
    PosData,
    Pr,
    ProtocolError,
    RawReply,
    Reply,
    SonarReply,
    Sp,
    Special,
    State,
    StateMask,
    StateReply,
    Tk,
    VelocityReply,
    Vm,
    Ws,
    decode_request,
)
from drivers.nomad200.integers import S16_MAX, S32_MAX
from drivers.nomad200.opcodes import STATE_REPLY_OPCODES
from drivers.nomad200.units import (
    CPU_VOLTAGE_RANGE,
    MOTOR_VOLTAGE_RANGE,
    m_to_inch,
    m_to_tenth_inch,
    rad_to_tenth_deg,
    tenth_deg_to_rad,
    tenth_inch_to_m,
    volts_to_raw,
)
from sim_backend.emulators.nomad200_faults import FaultConfig, FaultInjector
from sim_backend.emulators.nomad200_motion import Controller
from sim_backend.emulators.nomad200_transport import Transport
from sim_backend.simulator import SimRobot

SENSORS = 16
NO_ECHO = 255
IR_NOTHING = 15
WRAP_MS = 1 << 32
ZR_S = 120.0
_CPU_RAW = volts_to_raw(11.8, CPU_VOLTAGE_RANGE)
_MOTOR_RAW = volts_to_raw(12.4, MOTOR_VOLTAGE_RANGE)


def _s16(value: int) -> int:
    return max(-S16_MAX, min(S16_MAX, value))


def _s32(value: int) -> int:
    return max(-S32_MAX, min(S32_MAX, value))


def _tenths(angle: float) -> int:
    return rad_to_tenth_deg(angle) % 3600


def _to_wire(axis: int, value: float) -> int:
    return m_to_tenth_inch(value) if axis == 0 else rad_to_tenth_deg(value)


def _to_si(axis: int, value: int) -> float:
    return tenth_inch_to_m(value) if axis == 0 else tenth_deg_to_rad(value)


class Nomad200Emulator:
    """A Nomad 200 on one transport, backed by ``robot`` (see the module docstring)."""

    def __init__(
        self,
        robot: SimRobot,
        transport: Transport,
        *,
        lockstep: bool = False,
        faults: FaultConfig | None = None,
        monotonic: Callable[[], float] = time.monotonic,
    ) -> None:
        self.robot = robot
        self.transport = transport
        self.lockstep = lockstep
        self.faults = FaultInjector(faults or FaultConfig())
        self.control = Controller(robot)
        self.mask = StateMask()
        self.spoken: list[str] = []
        #: Requests served, by opcode name (tests and the benchmark read it).
        self.served: Counter[str] = Counter()
        self.requests = 0
        self.vanished = 0
        self.reappeared = 0
        self._monotonic = monotonic
        self._decoder = FrameDecoder()
        self._out: deque[tuple[float, bytes]] = deque()
        self._ws: tuple[tuple[bool, bool, bool], float] | None = None
        self._gone_at: float | None = None
        self._ring_on = True

    # ------------------------------------------------------------------ EmulatedDevice
    def fileno(self) -> int:
        return self.transport.fileno()

    def service(self, now_s: float) -> None:
        data = self.transport.read()
        if not data:
            return
        for frame in self._decoder.feed(data):
            if self._check_disappear():
                return  # this request finds the line gone
            self.requests += 1
            try:
                command = decode_request(frame)
            except ProtocolError:
                reply: Reply | None = NakReply()
            else:
                self.served[command.name()] += 1
                reply = self._answer(command)
            if reply is not None:
                self._send(reply)
        self._flush()

    def tick(self, now_s: float) -> None:
        self.transport.poll()
        if not self.lockstep:
            self.control.after_step()
            self._answer_ws_if_done()
        self._check_reappear()
        self._flush()

    def close(self) -> None:
        self.transport.close()

    # ------------------------------------------------------------------ time
    @property
    def clock_ms(self) -> int:
        return round(self.robot.t * 1000.0) % WRAP_MS

    def advance_to(self, t_end: float, until: Callable[[], bool] | None = None) -> None:
        """Lockstep: let simulated time run to ``t_end`` (or until ``until()`` holds).

        One ``robot.step`` covers the span unless the watchdog's deadline falls inside it or
        the controller has work at every physics step (a position move, a wait for stop).
        """
        r = self.robot
        fine = until is not None
        while r.t < t_end - 1e-9:
            if until is not None and until():
                break
            end = t_end
            if self.control.deadline > r.t:
                end = min(end, self.control.deadline)
            if fine or self.control.busy:
                end = min(end, r.t + r.p.physics_dt_s)
            r.step(max(end - r.t, 0.0))
            self.control.after_step()

    # ------------------------------------------------------------------ requests
    def _answer(self, cmd: Command) -> Reply | None:
        c = self.control
        op = cmd.OPCODE
        if isinstance(cmd, Vm | Pr | Pa | Mv):
            c.arm_watchdog()
        if isinstance(cmd, Ct):
            self.mask = cmd.mask
        elif isinstance(cmd, Vm):
            for axis, value in enumerate(self._si(cmd.trans, cmd.steer, cmd.turret)):
                c.set_velocity(axis, value)
        elif isinstance(cmd, Pr):
            for axis, value in enumerate(self._si(cmd.trans, cmd.steer, cmd.turret)):
                if value:
                    c.move_to(axis, c.axis_position(axis) + value)
        elif isinstance(cmd, Pa):
            for axis, value in enumerate(self._si(cmd.trans, cmd.steer, cmd.turret)):
                c.move_to(axis, value)
        elif isinstance(cmd, Mv):
            if not self._mixed_move(cmd):
                return NakReply()
        elif isinstance(cmd, Sp):
            for axis, value in enumerate((cmd.trans, cmd.steer, cmd.turret)):
                if _to_wire(axis, c.speed[axis]) != value:
                    c.speed[axis] = _to_si(axis, value)
        elif isinstance(cmd, Ac):
            self._accelerations(cmd)
        elif op == Opcode.ST:
            c.stop()
            self.robot.motors_on = True
        elif op == Opcode.LP:
            c.stop()
            self.robot.motors_on = False
        elif isinstance(cmd, Dp):
            c.define_position(tenth_inch_to_m(cmd.x), tenth_inch_to_m(cmd.y))
        elif isinstance(cmd, Da):
            c.define_angles(tenth_deg_to_rad(cmd.steer), tenth_deg_to_rad(cmd.turret))
        elif op == Opcode.ZR:
            c.stop()
            if self.lockstep:
                self.advance_to(self.robot.t + ZR_S, until=lambda: c.stopped((True,) * 3))
            c.define_angles(0.0, 0.0)
            c.define_position(0.0, 0.0)
        elif isinstance(cmd, Ws):
            return self._wait_for_stop(cmd)
        elif isinstance(cmd, ConfSn):
            self._configure_sonars(cmd)
        elif isinstance(cmd, ConfTm):
            c.motion_timeout_s = float(cmd.timeout)
            c.deadline = math.inf
            c.arm_watchdog()
        elif isinstance(cmd, ConfCp) and cmd.mode == CompassMode.CALIBRATE:
            return CompassCalibrationReply(100, 100, 100)
        elif isinstance(cmd, Tk):
            self.spoken.append(cmd.text)
        elif isinstance(cmd, Special):
            return self._special(cmd)
        elif op == Opcode.NAK:
            return NakReply()
        elif op not in STATE_REPLY_OPCODES:
            return self._sensor_reply(op)
        return StateReply(op, self.state())

    @staticmethod
    def _si(trans: int, steer: int, turret: int) -> tuple[float, float, float]:
        return tenth_inch_to_m(trans), tenth_deg_to_rad(steer), tenth_deg_to_rad(turret)

    def _mixed_move(self, cmd: Mv) -> bool:
        c = self.control
        specs = (cmd.trans, cmd.steer, cmd.turret)
        if any(s.mode in (MvMode.TQ, MvMode.MT) for s in specs):
            return False  # torque control is not simulated
        for axis, spec in enumerate(specs):
            si = _to_si(axis, spec.value)
            if spec.mode == MvMode.VM:
                c.set_velocity(axis, si)
            elif spec.mode == MvMode.PR:
                c.move_to(axis, c.axis_position(axis) + si)
            elif spec.mode == MvMode.PA:
                c.move_to(axis, si)
            elif spec.mode == MvMode.LP:
                c.set_velocity(axis, 0.0)
            elif spec.mode == MvMode.SP:
                c.speed[axis] = abs(si)
            elif spec.mode == MvMode.AC:
                c.set_acceleration(axis, abs(si))
        return True

    def _accelerations(self, cmd: Ac) -> None:
        lim = self.robot.p.limits
        now = (lim.accel_mps2, lim.steer_accel_radps2, lim.turret_accel_radps2)
        wire = (cmd.trans, cmd.steer, cmd.turret)
        for axis, (current, value) in enumerate(zip(now, wire, strict=True)):
            # Keep the simulator's own value when the wire says the same, so configuring the
            # usual limits leaves a run identical to one in process.
            if _to_wire(axis, current) != value:
                self.control.set_acceleration(axis, _to_si(axis, value))

    def _configure_sonars(self, cmd: ConfSn) -> None:
        r = self.robot
        ring = r.ring
        if cmd.rate == 0 or not cmd.order:
            ring.next_fire_t = math.inf
            self._ring_on = False
            return
        interval = cmd.rate * 0.004
        p = r.p
        if tuple(cmd.order) != p.firing_order or not math.isclose(interval, p.fire_interval_s):
            r.p = replace(p, firing_order=tuple(cmd.order), fire_interval_s=interval)
            ring.order_pos = 0
            ring.next_fire_t = r.t + interval
        elif not self._ring_on:
            ring.next_fire_t = r.t + interval
        self._ring_on = True

    def _wait_for_stop(self, cmd: Ws) -> Reply | None:
        axes = (cmd.trans, cmd.steer, cmd.turret)
        if self.lockstep:
            t_end = self.robot.t + cmd.timeout
            self.advance_to(t_end, until=lambda: self.control.stopped(axes))
            return StateReply(Opcode.WS, self.state())
        self._ws = (axes, self.robot.t + cmd.timeout)
        self._answer_ws_if_done()
        return None

    def _answer_ws_if_done(self) -> None:
        if self._ws is None:
            return
        axes, deadline = self._ws
        if self.control.stopped(axes) or self.robot.t >= deadline:
            self._ws = None
            self._send(StateReply(Opcode.WS, self.state()))

    def _special(self, cmd: Special) -> Reply:
        try:
            target = lockstep.parse_step_request(cmd)
        except ProtocolError:
            return NakReply()
        if target is None or not self.lockstep:
            return NakReply()  # a real-time robot cannot be stepped
        ahead = (target - self.clock_ms) % WRAP_MS
        if ahead < WRAP_MS // 2:  # a target in the past (a retransmission) passes no time
            self.advance_to(self.robot.t + ahead / 1000.0)
        return lockstep.step_reply(self.state(), self.mask)

    # ------------------------------------------------------------------ what the robot says
    def _pos(self, sense_ms: int | None = None, turret: float | None = None) -> PosData:
        pose = self.control.reported()
        r = self.robot
        ms = self.clock_ms
        return PosData(
            x=_s32(m_to_tenth_inch(pose.x)),
            y=_s32(m_to_tenth_inch(pose.y)),
            steer=_tenths(pose.steer),
            turret=_tenths(pose.turret if turret is None else turret),
            vel_trans=_s32(m_to_tenth_inch(r.v)),
            vel_steer=_s32(rad_to_tenth_deg(r.w)),
            vel_turret=_s32(rad_to_tenth_deg(r.wt)),
            config_time=ms,
            sense_time=ms if sense_ms is None else sense_ms,
        )

    def _sonar(self) -> tuple[int, ...]:
        return tuple(
            NO_ECHO if math.isnan(r) else min(NO_ECHO, m_to_inch(float(r)))
            for r in self.robot.ring.ranges
        )

    def _sonar_pos(self, i: int) -> PosData:
        ring = self.robot.ring
        steer = self.control.reported().steer
        relative = float(ring.yaw_robot[i]) - i * 2.0 * math.pi / SENSORS
        sense = round(float(ring.stamps[i]) * 1000.0) % WRAP_MS
        return self._pos(sense_ms=sense, turret=steer + relative)

    def state(self) -> State:
        """The state the current mask asks for, now."""
        m, r = self.mask, self.robot
        pose = self.control.reported()
        values: dict[str, object] = {
            "motor_status": 0b111 if r.motors_on else 0,
            "clock_ms": self.clock_ms,
            "cpu_voltage_raw": _CPU_RAW,
            "motor_voltage_raw": _MOTOR_RAW,
        }
        sonar = self._sonar()
        values["sonar"] = tuple(sonar[i] if i in m.sonar else None for i in range(SENSORS))
        values["ir"] = tuple(IR_NOTHING if i in m.ir else None for i in range(SENSORS))
        if m.pos_sonar:
            values["sonar_pos"] = tuple(
                self._sonar_pos(i) if i in m.sonar else None for i in range(SENSORS)
            )
        if m.pos_ir:
            values["ir_pos"] = tuple(self._pos() if i in m.ir else None for i in range(SENSORS))
        if m.bumper:
            values["bumper"] = 1 if r.bumper else 0
            if m.pos_bumper:
                values["bumper_pos"] = self._pos()
        wire = {
            "x": _s16(m_to_tenth_inch(pose.x)),
            "y": _s16(m_to_tenth_inch(pose.y)),
            "steer": _tenths(pose.steer),
            "turret": _tenths(pose.turret),
            "vel_trans": _s16(m_to_tenth_inch(r.v)),
            "vel_steer": _s16(rad_to_tenth_deg(r.w)),
            "vel_turret": _s16(rad_to_tenth_deg(r.wt)),
        }
        for name, value in wire.items():
            if getattr(m, name):
                values[name] = value
        if m.compass:
            values["compass"] = _tenths(r.pose.theta)
            if m.pos_compass:
                values["compass_pos"] = self._pos()
        if m.laser:
            values["laser"] = ()
            if m.pos_laser:
                values["laser_pos"] = self._pos()
        return State(**values)  # type: ignore[arg-type]

    def _sensor_reply(self, op: Opcode) -> Reply:
        m, ms = self.mask, self.clock_ms
        if op == Opcode.GET_SN:
            pos = tuple(self._sonar_pos(i) for i in range(SENSORS)) if m.pos_sonar else None
            return SonarReply(self._sonar(), pos, ms)
        if op == Opcode.GET_IR:
            pos = tuple(self._pos() for _ in range(SENSORS)) if m.pos_ir else None
            return IrReply((IR_NOTHING,) * SENSORS, pos, ms)
        if op == Opcode.GET_BP:
            bumper = 1 if self.robot.bumper else 0
            return BumperReply(bumper, self._pos() if m.pos_bumper else None, ms)
        if op == Opcode.GET_CP:
            heading = _tenths(self.robot.pose.theta)
            return CompassReply(heading, self._pos() if m.pos_compass else None, ms)
        if op == Opcode.GET_RC:
            pose = self.control.reported()
            return ConfigurationReply(
                _s16(m_to_tenth_inch(pose.x)),
                _s16(m_to_tenth_inch(pose.y)),
                _tenths(pose.steer),
                _tenths(pose.turret),
            )
        if op == Opcode.GET_RV:
            r = self.robot
            w, wt = rad_to_tenth_deg(r.w), rad_to_tenth_deg(r.wt)
            return VelocityReply(_s16(m_to_tenth_inch(r.v)), _s16(w), _s16(wt))
        if op in (Opcode.GET_RA, Opcode.GET_LS, Opcode.GET_SG):
            return RawReply(op, b"")
        return NakReply()

    # ------------------------------------------------------------------ the line
    def _send(self, reply: Reply) -> None:
        frame = reply.encode(self.mask)
        faulted = self.faults.apply(frame, self.requests)
        if faulted is None:
            return
        data, delay = faulted
        now = self._monotonic()
        at = max(now + delay, self._out[-1][0] if self._out else now)
        self._out.append((at, data))

    def _flush(self) -> None:
        now = self._monotonic()
        while self._out and self._out[0][0] <= now:
            self.transport.write(self._out.popleft()[1])

    def _check_disappear(self) -> bool:
        c = self.faults.config
        if self._gone_at is not None or self.vanished:
            return self._gone_at is not None
        by_count = c.disappear_after_requests is not None and (
            self.requests >= c.disappear_after_requests
        )
        if by_count or self.robot.t >= c.disappear_after_s:
            self.transport.disappear()
            self._gone_at = self._monotonic()
            self.vanished += 1
            self._decoder = FrameDecoder()
            self._out.clear()
            self._ws = None
            return True
        return False

    def _check_reappear(self) -> None:
        after = self.faults.config.reappear_after_s
        if self._gone_at is None or after is None:
            return
        if self._monotonic() - self._gone_at >= after:
            self.transport.reappear()
            self._gone_at = None
            self.reappeared += 1

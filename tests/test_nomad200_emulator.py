"""The Nomad 200 emulator, spoken to byte by byte over its pty, and ``tslam emulate nomad200``
run as a user runs it (its own process, loopback only, always killed)."""

from __future__ import annotations

import json
import math
import signal
import subprocess

import numpy as np
import pytest
import serial

from drivers.nomad200.codec import (
    ConfSn,
    Ct,
    Da,
    Dp,
    FrameDecoder,
    GetBp,
    GetRc,
    GetSn,
    Gs,
    Lp,
    Mv,
    MvAxis,
    MvMode,
    NakReply,
    Pr,
    Reply,
    SonarReply,
    Special,
    St,
    StateMask,
    StateReply,
    Tk,
    Vm,
    Ws,
    Zr,
    decode_reply,
)
from drivers.nomad200.lockstep import parse_step_reply, step_request
from hal.types import Twist
from sim_backend.emulators.nomad200_faults import FaultConfig, FaultInjector
from tests.nomad200_rig import Rig
from tslam.programs.cli import main
from tslam.programs.emulated import emulator_command, read_ready_line, stop_process

POSE = StateMask(x=True, y=True, steer=True, turret=True, vel_trans=True)


class Client:
    """The host side, by hand: one request, one reply, read with the mask last set."""

    def __init__(self, port: str) -> None:
        self.port = serial.serial_for_url(port, baudrate=9600, timeout=0.05)
        self.mask = StateMask()

    def raw(self, data: bytes, timeout: float = 5.0) -> list:
        self.port.reset_input_buffer()
        self.port.write(data)
        decoder = FrameDecoder()
        frames: list = []
        for _ in range(int(timeout / 0.05)):
            frames += decoder.feed(self.port.read(max(1, self.port.in_waiting)))
            if frames:
                break
        return frames

    def ask(self, command, timeout: float = 5.0) -> Reply:
        if isinstance(command, Ct):
            self.mask = command.mask
        frames = self.raw(command.encode(), timeout)
        assert len(frames) == 1, f"no reply to {command}"
        return decode_reply(frames[0], self.mask, request=command.OPCODE)

    def close(self) -> None:
        self.port.close()


@pytest.fixture
def rig():
    with Rig() as r:
        yield r


@pytest.fixture
def client(rig):
    c = Client(rig.port)
    yield c
    c.close()


def test_worked_frame_gs_is_answered_with_the_power_up_state(client):
    frames = client.raw(bytes.fromhex("0102 0007 0a5c".replace(" ", "")))
    reply = decode_reply(frames[0], StateMask(), request=7)
    assert isinstance(reply, StateReply)
    assert len(frames[0].payload) == 7  # the tail only: motors, clock, two voltages
    assert reply.state.motors_active == (True, True, True)


def test_replies_follow_the_mask_set_with_ct(client):
    reply = client.ask(Ct(POSE))
    assert reply.state.x == 0 and reply.state.sonar == (None,) * 16
    full = StateMask.full()
    state = client.ask(Ct(full)).state
    assert all(r is not None for r in state.sonar) and all(p is not None for p in state.sonar_pos)
    assert state.ir == (15,) * 16 and state.laser == () and state.compass is not None


def test_vm_moves_and_st_stops(client, rig):
    client.ask(Ct(POSE))
    client.ask(Vm(100, 0, 0))
    step = client.ask(step_request(2000))
    state = parse_step_reply(step, client.mask)
    assert state.clock_ms == 2000
    assert 150 < state.x < 200  # 10 in/s for 2 s, less the acceleration
    client.ask(St())
    client.ask(step_request(4000))
    assert client.ask(Gs()).state.vel_trans == 0


def test_a_step_to_a_time_already_passed_passes_none(client):
    client.ask(step_request(1000))
    again = parse_step_reply(client.ask(step_request(1000)), client.mask)
    assert again.clock_ms == 1000


def test_vm_is_capped_by_sp(client, rig):
    client.ask(Vm(5000, 0, 0))
    assert rig.robot.cmd_v == pytest.approx(0.508)


def test_dp_da_and_zr_redefine_the_reported_pose(client):
    client.ask(Ct(POSE))
    client.ask(Dp(1000, -2000))
    client.ask(Da(900, 1800))
    rc = client.ask(GetRc())
    assert (rc.x, rc.y, rc.steer, rc.turret) == (1000, -2000, 900, 1800)
    client.ask(Vm(100, 0, 0))  # along the new heading: +y
    state = parse_step_reply(client.ask(step_request(1000)), client.mask)
    assert state.y > -2000 + 50 and abs(state.x - 1000) <= 1
    state = client.ask(Zr(), timeout=10.0).state
    assert (state.x, state.y, state.steer, state.turret) == (0, 0, 0, 0)


def test_pr_moves_by_the_distance_and_ws_waits_for_it(client):
    client.ask(Ct(POSE))
    client.ask(Pr(1000, 900, 0))  # 100 inches, 90 degrees of steering
    state = client.ask(Ws(True, True, False, 30), timeout=10.0).state
    assert state.vel_trans == 0
    assert math.hypot(state.x, state.y) == pytest.approx(1000 * 2 / math.pi * math.sqrt(2), rel=0.2)
    assert state.steer == pytest.approx(900, abs=2)


def test_mv_mixes_modes_and_refuses_torque(client, rig):
    client.ask(Mv(MvAxis(MvMode.VM, 100), MvAxis(MvMode.IGNORE, 0), MvAxis(MvMode.VM, -200)))
    assert rig.robot.cmd_v == pytest.approx(0.254) and rig.robot.cmd_wt == pytest.approx(
        -math.radians(20.0)
    )
    assert isinstance(client.ask(Mv(MvAxis(MvMode.TQ, 10))), NakReply)


def test_lp_turns_the_motors_off(client, rig):
    assert client.ask(Lp()).state.motor_status == 0
    assert not rig.robot.motors_on
    assert client.ask(Vm(0, 0, 0)).state.motor_status == 0b111


def test_conf_sn_rate_zero_stops_the_ring(client, rig):
    client.ask(ConfSn(0, ()))
    fired = rig.robot.ring.fired
    client.ask(step_request(3000))
    assert rig.robot.ring.fired == fired
    client.ask(ConfSn(25, (0, 8)))
    client.ask(step_request(4000))
    assert rig.robot.ring.fired - fired == 10  # two transducers, one every 100 ms
    assert rig.robot.p.firing_order == (0, 8)


def test_sensor_requests(client, rig):
    sonar = client.ask(GetSn())
    assert isinstance(sonar, SonarReply) and len(sonar.readings) == 16 and sonar.pos is None
    rig.robot.bumper = True
    assert client.ask(GetBp()).value == 1


def test_talk_is_kept_and_unknown_user_packets_are_refused(client, rig):
    client.ask(Tk("hello"))
    assert rig.emu.spoken == ["hello"]
    assert isinstance(client.ask(Special(b"user code")), NakReply)


def test_a_broken_request_gets_no_answer_and_the_next_one_does(client):
    bad = bytearray(Gs().encode())
    bad[-2] ^= 0xFF
    assert client.raw(bytes(bad), timeout=0.3) == []
    assert isinstance(client.ask(Gs()), StateReply)


def test_a_real_time_emulator_cannot_be_stepped():
    with Rig(lockstep=False) as rig:
        c = Client(rig.port)
        try:
            assert isinstance(c.ask(step_request(1000)), NakReply)
        finally:
            c.close()


def test_fault_injection_is_seeded():
    frame = Gs().encode()

    def outcomes(seed: int) -> list:
        inj = FaultInjector(
            FaultConfig(drop=0.2, corrupt=0.2, truncate=0.2, garbage=0.2, seed=seed)
        )
        return [inj.apply(frame, k) for k in range(1, 200)]

    assert outcomes(7) == outcomes(7)
    assert outcomes(7) != outcomes(8)
    kinds = FaultInjector(FaultConfig(drop=0.25, corrupt=0.25, truncate=0.25, garbage=0.25))
    for k in range(1, 400):
        kinds.apply(frame, k)
    assert set(kinds.injected) == {"drop", "corrupt", "truncate", "garbage"}
    clean = FaultInjector(FaultConfig(drop=1.0, after_requests=5))
    assert [clean.apply(frame, k) for k in range(1, 6)] == [(frame, 0.0)] * 5
    assert clean.apply(frame, 6) is None


def test_bad_fault_options_are_refused():
    with pytest.raises(ValueError, match="must not exceed 1"):
        FaultConfig(drop=0.6, corrupt=0.6)


def test_lockstep_runs_repeat_exactly():
    def run() -> list:
        with Rig(drift="paper", seed=11) as rig, rig.backend() as b:
            out = []
            for k in range(40):
                b.command(Twist(0.3, math.radians(10.0 * math.sin(k / 5)), 0.1))
                b.clock.sleep(0.1)
                odo, scan = b.odometry(), b.scan()
                ranges = tuple(float(r) for r in np.nan_to_num(scan.ranges_m, nan=-1.0))
                out.append((odo.x_m, odo.y_m, odo.heading_rad, ranges))
            return out

    assert run() == run()


# --------------------------------------------------------------------------- the command


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--world", "no-such-world"], "no-such-world"),
        (["--world", "fig12", "--listen", "udp:1.2.3.4"], "--listen must look like"),
        (["--world", "fig12", "--drop", "2"], "must be in 0..1"),
        (["--world", "fig12", "--time-scale", "0"], "--time-scale"),
    ],
)
def test_user_mistakes_are_one_line(capsys, argv, message):
    code = main(["emulate", "nomad200", *argv])
    _, err = capsys.readouterr()
    assert code == 2
    assert message in err and err.count("\n") == 1 and "Traceback" not in err


def _start(argv: list[str]) -> subprocess.Popen:
    return subprocess.Popen(
        argv,
        stdin=subprocess.DEVNULL,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )


def test_serves_tcp_on_loopback_and_exits_cleanly_on_sigterm():
    cmd = emulator_command("fig12", 2, "none", lockstep=False)
    cmd[cmd.index("--pty")] = "--listen=tcp:127.0.0.1:0"
    proc = _start(cmd)
    try:
        ready = read_ready_line(proc, 120.0)
        assert ready["transport"] == "tcp" and ready["port"].startswith("socket://127.0.0.1:")
        from drivers.nomad200.device import Nomad200Backend

        with Nomad200Backend.from_config({"port": ready["port"], "time_scale": 1.0}) as b:
            b.command(Twist(0.2, 0.0, 0.0))
            b.clock.sleep(0.5)
            assert b.odometry().x_m > 0.0
        proc.send_signal(signal.SIGTERM)
        assert proc.wait(30) == 0
    finally:
        stop_process(proc)


def test_the_pty_comes_back_behind_its_link_across_processes(tmp_path):
    link = tmp_path / "nomad200"
    extra = [
        "--link",
        str(link),
        "--disappear-after-requests",
        "10",
        "--reappear-after-s",
        "0.5",
    ]
    proc = _start(emulator_command("fig12", 2, "none", extra))
    try:
        ready = read_ready_line(proc, 120.0)
        assert ready["port"] == str(link) and json.dumps(ready)
        from drivers.nomad200.device import Nomad200Backend

        options = {"port": str(link), "lockstep": True, "reconnect_backoff_s": 0.05}
        with Nomad200Backend.from_config(options) as b:
            for _ in range(6):
                b.command(Twist(0.2, 0.0, 0.0))
                b.clock.sleep(0.1)
            assert b.link.reconnects == 1
            assert b.clock.now() == pytest.approx(0.6)
    finally:
        stop_process(proc)


def test_faults_injected_across_processes_are_named():
    from hal.errors import DeviceTimeoutError
    from tslam.programs.emulated import emulated_nomad200

    extra = ["--drop", "1", "--faults-after", "8"]
    with emulated_nomad200(
        "fig12", 2, "none", emulator_args=extra, reply_timeout_s=0.2, retries=1
    ) as b:
        b.configure()
        b.activate()
        b.command(Twist(0.2, 0.0, 0.0))
        b.clock.sleep(0.1)
        with pytest.raises(DeviceTimeoutError, match="reply timeout for 0x05 \\(VM\\)"):
            b.command(Twist(0.2, 0.0, 0.0))
